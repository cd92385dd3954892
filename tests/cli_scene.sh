#!/usr/bin/env bash
# End-to-end checks of `mrcheck factory` and the big-scene options of
# `mrcheck render`: the synthetic factory and its views are written; culling,
# batching, instancing and occlusion culling do not change the image; the
# LOD cache is written next to the scene, reused, and ignored when damaged
# (by render, and by replay for a big scene);
# bad values give one line on stderr and a non-zero exit.
# Usage: cli_scene.sh MRCHECK TMPDIR. Exit 77 = skipped (no GL device: mrcheck exit 69).
set -u
mr=$1
tmp=$2
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"

if "$mr" factory --halls 1 --out "$tmp/plant/s.glb" --views "$tmp/views" >"$tmp/synth.log" 2>&1; then
  for f in plant/s.glb views/view_floor.json views/view_aisle.json views/view_overview.json; do
    [ -s "$tmp/$f" ] && ok || bad "factory did not write $f"
  done
  grep -q "2317 nodes" "$tmp/synth.log" && ok || bad "factory summary: $(cat "$tmp/synth.log")"
else
  bad "synth failed: $(cat "$tmp/synth.log")"
fi
v=$tmp/views/view_floor.json
r() { "$mr" render --scene "$tmp/plant/s.glb" --view "$v" --size 240x180 --lod off "$@"; }
r --out "$tmp/all.png" --verbose 2>"$tmp/all.err"
rc=$?
if [ $rc -eq "$MR_EXIT_NODEVICE" ]; then echo "cli_scene: SKIPPED: no GL device: $(cat "$tmp/all.err")"; exit 77; fi
[ $rc -eq 0 ] && ok || bad "render failed (exit $rc): $(cat "$tmp/all.err")"
grep -q "geometry: .* nodes visible" "$tmp/all.err" && ok || bad "verbose draw counts missing: $(cat "$tmp/all.err")"
grep -q "peak RSS" "$tmp/all.err" && ok || bad "verbose load report missing"
r --out "$tmp/none.png" --cull off --batch off --instancing off 2>"$tmp/none.err" \
  && cmp -s "$tmp/all.png" "$tmp/none.png" && ok || bad "culling/batching/instancing changed the image"
r --out "$tmp/occl.png" --occlusion on 2>"$tmp/occl.err" \
  && cmp -s "$tmp/all.png" "$tmp/occl.png" && ok || bad "occlusion culling changed the image"

# LOD cache: written, reused, a damaged one ignored (with a warning). A
# tiny scene keeps this quick: the levels themselves and the cache's checks
# are tested in test_cull_lod.
pos_b64=$(printf '\000\000\000\000\000\000\000\000\000\000\000\000\000\000\200\077\000\000\000\000\000\000\000\000\000\000\000\000\000\000\200\077\000\000\000\000' | base64 -w0)
cat >"$tmp/tri.gltf" <<J
{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0,"translation":[0,0,3]}],
 "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
 "buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,$pos_b64"}],
 "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36}],
 "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}]}
J
rl() { "$mr" render --scene "$tmp/tri.gltf" --view "$v" --size 64x48 --lod on --out "$@"; }
rl "$tmp/lod1.png" --verbose 2>"$tmp/lod1.err" && [ -s "$tmp/tri.gltf.mrlod" ] && grep -q "LOD: .* built" "$tmp/lod1.err" \
  && ok || bad "LOD cache not written: $(cat "$tmp/lod1.err")"
rl "$tmp/lod2.png" --verbose 2>"$tmp/lod2.err" && grep -q "read from the cache" "$tmp/lod2.err" \
  && cmp -s "$tmp/lod1.png" "$tmp/lod2.png" && ok || bad "LOD cache not reused: $(cat "$tmp/lod2.err")"
printf 'x' >>"$tmp/tri.gltf.mrlod"
rl "$tmp/lod3.png" 2>"$tmp/lod3.err" && grep -q "ignored" "$tmp/lod3.err" && cmp -s "$tmp/lod1.png" "$tmp/lod3.png" \
  && ok || bad "damaged LOD cache: $(cat "$tmp/lod3.err")"
# The levels above the part: --hlod auto leaves them out for the factory
# (under 1M triangles: nothing read or built), --hlod on builds and caches
# them in <scene>.mrhlod and draws proxies, the cache is reused for the same
# image, a damaged one is ignored and rebuilt, --hlod off draws none.
v2=$tmp/views/view_overview.json
rh() { "$mr" render --scene "$tmp/plant/s.glb" --view "$v2" --size 120x90 --lod on --verbose "$@"; }
rh --out "$tmp/h0.png" 2>"$tmp/h0.err" && ! grep -q "hierarchy" "$tmp/h0.err" && [ ! -e "$tmp/plant/s.glb.mrhlod" ] \
  && ok || bad "--hlod auto loaded a hierarchy for a small scene: $(cat "$tmp/h0.err")"
rh --out "$tmp/h1.png" --hlod on 2>"$tmp/h1.err" && grep -q "LOD hierarchy: .* built" "$tmp/h1.err" \
  && grep -q "render: LOD hierarchy: [1-9][0-9]* proxies" "$tmp/h1.err" && [ -s "$tmp/plant/s.glb.mrhlod" ] \
  && ok || bad "--hlod on built or drew no hierarchy: $(cat "$tmp/h1.err")"
rh --out "$tmp/h2.png" --hlod on 2>"$tmp/h2.err" && grep -q "LOD hierarchy: .* read from the cache" "$tmp/h2.err" \
  && cmp -s "$tmp/h1.png" "$tmp/h2.png" && ok || bad "hierarchy cache not reused: $(cat "$tmp/h2.err")"
head -c 5000 "$tmp/plant/s.glb.mrhlod" >"$tmp/short" && mv "$tmp/short" "$tmp/plant/s.glb.mrhlod"
rh --out "$tmp/h3.png" --hlod on 2>"$tmp/h3.err" && grep -q "mrhlod: ignored" "$tmp/h3.err" \
  && grep -q "LOD hierarchy: .* built" "$tmp/h3.err" && cmp -s "$tmp/h1.png" "$tmp/h3.png" \
  && ok || bad "truncated hierarchy cache: $(cat "$tmp/h3.err")"
rh --out "$tmp/h4.png" --hlod off 2>"$tmp/h4.err" && ! grep -q "hierarchy" "$tmp/h4.err" \
  && ok || bad "--hlod off: $(cat "$tmp/h4.err")"
rh --out "$tmp/h5.png" --hlod maybe 2>"$tmp/h5.err"
[ $? -eq 2 ] && [ "$(wc -l <"$tmp/h5.err")" -eq 1 ] && grep -q -- "--hlod must be" "$tmp/h5.err" \
  && ok || bad "bad --hlod: $(cat "$tmp/h5.err")"
# replay draws levels as render does: --lod on here (the demo hall, which
# the demo recording sees, is under --lod auto's 500k triangles), through
# the same cache next to the scene; --lod auto leaves them out for it.
rec="$(dirname "$0")/../recordings/demo"
cp "$(dirname "$0")/../configs/scenes/demo_planned.json" "$tmp/hall.json"
rp() { "$mr" replay "$rec" --scene "$tmp/hall.json" --every 60 --out "$@" --verbose; }
simplified() { # simplified ERRFILE: the instances the replay drew at a simplified level
  sed -n 's/.*replay: [0-9]* triangles submitted over the overlays, \([0-9]*\) instances at a simplified level.*/\1/p' "$1"
}
rp "$tmp/rp1" --lod on 2>"$tmp/rp1.err" && grep -q "LOD: .* built" "$tmp/rp1.err" && [ -s "$tmp/hall.json.mrlod" ] \
  && [ "$(simplified "$tmp/rp1.err")" -gt 0 ] \
  && ok || bad "replay --lod on built or drew no levels: $(tail -3 "$tmp/rp1.err")"
same_overlays() { # same_overlays DIR1 DIR2: both have the same overlay PNGs, at least one
  local f n=0
  for f in "$1"/overlay_*.png; do
    [ -f "$f" ] && cmp -s "$f" "$2/$(basename "$f")" || return 1
    n=$((n + 1))
  done
  [ "$n" -gt 0 ]
}
rp "$tmp/rp2" --lod on 2>"$tmp/rp2.err" && grep -q "read from the cache" "$tmp/rp2.err" && same_overlays "$tmp/rp1" "$tmp/rp2" \
  && [ "$(simplified "$tmp/rp2.err")" = "$(simplified "$tmp/rp1.err")" ] \
  && ok || bad "replay did not reuse the LOD cache or drew other images: $(tail -3 "$tmp/rp2.err")"
for mode in off auto; do
  rp "$tmp/rp_$mode" --lod $mode 2>"$tmp/rp_$mode.err" && ! grep -q "LOD:" "$tmp/rp_$mode.err" \
    && [ "$(simplified "$tmp/rp_$mode.err")" = 0 ] && ok || bad "replay --lod $mode: $(tail -3 "$tmp/rp_$mode.err")"
done
expect_fail replay_bad_lod "$tmp/rp4" -- "$mr" replay "$rec" --scene "$tmp/hall.json" --out "$tmp/rp4" --lod sometimes

expect_fail bad_cull "$tmp/x.png" -- r --out "$tmp/x.png" --cull maybe
expect_fail bad_tolerance "$tmp/x.png" -- r --out "$tmp/x.png" --lod-tolerance -1
expect_fail bad_lod "$tmp/x.png" -- r --out "$tmp/x.png" --lod sometimes
expect_fail synth_no_out "" -- "$mr" factory --halls 2
expect_fail synth_bad_count "$tmp/y.glb" -- "$mr" factory --out "$tmp/y.glb" --triangles lots
expect_fail synth_both "$tmp/y.glb" -- "$mr" factory --out "$tmp/y.glb" --triangles 1M --halls 3
expect_fail bench_bad_sizes "" -- "$mr" bench scene --sizes 5Q --out "$tmp/b"
# Unique CAD-like geometry (issue 17): every part its own mesh, in millimetres.
if "$mr" factory --unique --unit 1000 --triangles 40k --out "$tmp/cad/c.glb" --views "$tmp/cadviews" >"$tmp/cad.log" 2>&1; then
  [ -s "$tmp/cad/c.glb" ] && [ -s "$tmp/cadviews/view_overview.json" ] && ok || bad "factory --unique did not write its files"
  grep -q "2 unique parts in unit 1000 per metre, 3 nodes, 3 meshes" "$tmp/cad.log" && ok || bad "factory --unique summary: $(cat "$tmp/cad.log")"
else
  bad "factory --unique failed: $(cat "$tmp/cad.log")"
fi
# issue 17 (lane cluster): the meshlets cached beside the file; a damaged
# cache is ignored with a warning (same image, exit 0) and rewritten.
if [ -s "$tmp/cad/c.glb" ]; then
  rc_() { "$mr" render --scene "$tmp/cad/c.glb" --view "$tmp/cadviews/view_floor.json" --size 160x120 --lod off --verbose "$@"; }
  rc_ --out "$tmp/cad/a.png" 2>"$tmp/cad/a.err" && grep -q "0 levels from the cache, 2 built.*(cache written)" "$tmp/cad/a.err" &&
    [ -s "$tmp/cad/c.glb.mrclu" ] && ok || bad "first render: no meshlet cache written: $(cat "$tmp/cad/a.err")"
  rc_ --out "$tmp/cad/b.png" 2>"$tmp/cad/b.err" && grep -q "2 levels from the cache, 0 built" "$tmp/cad/b.err" &&
    cmp -s "$tmp/cad/a.png" "$tmp/cad/b.png" && ok || bad "second render: meshlets not from the cache: $(cat "$tmp/cad/b.err")"
  head -c 1000 "$tmp/cad/c.glb.mrclu" >"$tmp/cad/short" && mv "$tmp/cad/short" "$tmp/cad/c.glb.mrclu"
  rc_ --out "$tmp/cad/c.png" 2>"$tmp/cad/c.err" && grep -q "c.glb.mrclu: ignored (truncated" "$tmp/cad/c.err" &&
    grep -q "2 built.*(cache written)" "$tmp/cad/c.err" && cmp -s "$tmp/cad/a.png" "$tmp/cad/c.png" && ok ||
    bad "truncated meshlet cache: $(cat "$tmp/cad/c.err")"
  rc_ --out "$tmp/cad/d.png" --lod-cache off 2>"$tmp/cad/d.err" && grep -q "0 levels from the cache, 2 built" "$tmp/cad/d.err" &&
    ! grep -q "cache written" "$tmp/cad/d.err" && ok || bad "--lod-cache off: $(cat "$tmp/cad/d.err")"
fi
expect_fail factory_bad_unit "$tmp/cad/bad.glb" -- "$mr" factory --unique --unit 0 --out "$tmp/cad/bad.glb"
expect_fail factory_unit_alone "$tmp/cad/bad.glb" -- "$mr" factory --unit 1000 --out "$tmp/cad/bad.glb"
expect_fail factory_unique_halls "$tmp/cad/bad.glb" -- "$mr" factory --unique --halls 2 --out "$tmp/cad/bad.glb"
expect_fail bench_bad_unit "" -- "$mr" bench scene --unique --unit -1 --out "$tmp/b"
# bench scene --unique at one part, twice into one folder: the
# hierarchy's columns at the end (the hier row: 9 configs x 3 views), each image against "none" (0 for
# itself), the first build's rate of LOD and meshlets, the Goal lines in the log and the CSV, the LOD cache removed
# before each first build, --full-detail-frames for no-lod and none.
bu() { "$mr" bench scene --unique --sizes 10k --frames 1 --size 64x48 --out "$tmp/bu" "$@"; }
if bu >"$tmp/bu1.log" 2>&1 && bu --full-detail-frames 2 >"$tmp/bu.log" 2>&1; then
  csv=$tmp/bu/bench_scene_unique.csv
  head -1 "$csv" | grep -q ',lod_cached_s,unit,image_diff_pct,image_edge_pct,open_first_s,open_cached_s,timed_frames,frame_cpu_ms,cluster_build_s,lod_cluster_mtris_s,hlod_s,hlod_cached_s,hlod_stored_triangles,hlod_proxies,hlod_triangles$' && ok ||
    bad "bench scene --unique columns: $(head -1 "$csv")"
  [ "$(grep -vc '^#' "$csv")" = 28 ] && [ "$(grep -c ',hier,' "$csv")" = 3 ] && ok || bad "bench scene --unique: not 27 rows with 3 hier"
  awk -F, '!/^#/ && NR > 1 && (NF != 39 || $35 < 0 || $36 < 0 || $37 < 0 || $38 < 0 || $39 < 0 || $32 < 0 || $33 < 0 || !($34 > 0) || $11 != 0 || ($14 == "none" && $27 != 0) || $31 != ($14 == "none" || $14 == "no-lod" ? 2 : 1)) { b = 1 }
           END { exit b }' "$csv" && ok || bad "bench scene --unique rows (fields, first build, none's diff, frames): $(cat "$csv")"
  [ "$(grep -c '^# Goal image 10k ' "$csv")" = 3 ] && grep -q '^Goal image 10k overview: all differs from none in ' "$tmp/bu.log" &&
    grep -q '^Goal floor: .*not measured' "$tmp/bu.log" && ok || bad "bench scene --unique Goal lines: $(cat "$tmp/bu.log")"
else
  bad "bench scene --unique failed: $(cat "$tmp/bu1.log" "$tmp/bu.log")"
fi
# Two sizes of parts big enough for meshlets (20k triangles): each size
# uploads with the default draw parameters, and its second open reads the
# meshlets back from their cache (the last case of the first size once left
# cluster culling off for the second size's uploads).
if "$mr" bench scene --unique --sizes 20k,40k --frames 1 --full-detail-frames 1 --size 64x48 --out "$tmp/bm" >"$tmp/bm.log" 2>&1; then
  ! grep -q 'was not used' "$tmp/bm.log" && [ -s "$tmp/bm/cad_2parts.glb.mrclu" ] && ok ||
    bad "bench scene --unique: a cache not used: $(grep -i 'cache' "$tmp/bm.log")"
else
  bad "bench scene --unique at 20k,40k failed: $(cat "$tmp/bm.log")"
fi
[ ! -e "$tmp/x.png" ] && [ ! -e "$tmp/y.glb" ] && ok || bad "output left behind"

cli_finish cli_scene
