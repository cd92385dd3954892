// Level 0 of the AO's depth mip chain, a copy of the G-buffer's
// reversed-Z depth into an R32F texture that glGenerateTextureMipmap can
// box-filter (a depth texture cannot be copied into a colour one). The
// box average of d = near / z is exact on a plane (1/z is affine in the
// image), so a far sample on a plane reads the same point from any level.
#include "mr_bindings.h"

layout(binding = MR_TEX_AO_MIP_SRC) uniform sampler2D u_src;

layout(location = 0) out float o_d;

void main() { o_d = texelFetch(u_src, ivec2(gl_FragCoord.xy), 0).r; }
