/* lod.c's build kernel (simplification and the certified bound: the first
 * load's hot loop) compiled again with -march=x86-64-v3
 * (CMakeLists.txt), exported as mr_lod_build_mesh_v3 for lod.c to call on
 * CPUs with AVX2 and FMA. Same source, so the same algorithm; the compiler
 * only has more instructions to choose from (measured: 8 % less CPU,
 * identical levels on the 2M unique factory). Empty where the build does
 * not make it (another architecture or compiler). */
#ifdef MR_LOD_HAVE_V3
#define MR_LOD_KERNEL_V3 1
#include "lod.c"
#else
typedef int mr_lod_v3_not_built; /* (ISO C wants a declaration in every file) */
#endif
