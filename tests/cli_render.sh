#!/usr/bin/env bash
# End-to-end checks of `mrcheck demo` and `mrcheck render`, and of bad input:
# every failure must print exactly one line on stderr, exit non-zero, and
# leave no output file (not even a temporary one) behind.
# Usage: cli_render.sh MRCHECK TMPDIR. Exit 77 = skipped (no GL device: mrcheck exit 69).
set -u
mr=$1
tmp=$2
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"

# The demo writes the files the other cases use.
demo_or_exit cli_render "$mr" "$tmp/demo"
d=$tmp/demo
for f in hall_planned.glb hall_built.glb markers.json discrepancies.json camera.json scene_planned.json \
         frames/frame_000.png overlay/overlay_000.png views/view_000.json; do
  [ -s "$d/$f" ] && ok || bad "demo did not write $f"
done

# A good render, with --verbose pass list and --aux outputs.
if "$mr" render --scene "$d/scene_planned.json" --view "$d/views/view_000.json" --out "$tmp/good.png" \
     --video "$d/frames/frame_000.png" --alpha 0.3 --aux "$tmp/aux" --verbose 2>"$tmp/good.err"; then
  [ -s "$tmp/good.png" ] && ok || bad "render wrote no PNG"
  grep -q "passes: gbuffer shade overlay" "$tmp/good.err" && ok || bad "verbose pass list missing: $(cat "$tmp/good.err")"
  [ -s "$tmp/aux/depth.pfm" ] && [ -s "$tmp/aux/normal.pfm" ] && ok || bad "aux files missing"
else
  bad "good render failed: $(cat "$tmp/good.err")"
fi
# Without video there is no overlay pass.
"$mr" render --scene "$d/hall_planned.glb" --view "$d/views/view_001.json" --out "$tmp/plain.png" --verbose 2>"$tmp/plain.err" \
  && grep -q "passes: gbuffer shade;" "$tmp/plain.err" && ok || bad "plain render / pass list: $(cat "$tmp/plain.err")"
# glTF recognised by content: a .glb named .gltf and a JSON named .glb.
cp "$d/hall_planned.glb" "$tmp/misnamed.gltf"
"$mr" render --scene "$tmp/misnamed.gltf" --view "$d/views/view_001.json" --out "$tmp/misnamed.png" 2>/dev/null \
  && cmp -s "$tmp/misnamed.png" "$tmp/plain.png" && ok || bad "misnamed .glb did not render the same image"

# --- bad input -----------------------------------------------------------
v=$d/views/view_000.json
s=$d/scene_planned.json
# The shipped scene configs build the demo hall themselves ("demo": ...), so
# they work on a fresh clone without demo-out/: the same picture as the
# files `mrcheck demo` wrote, and the shipped recording replays with them.
src=$(cd "$(dirname "$0")/.." && pwd)
for k in planned built; do
  "$mr" render --scene "$src/configs/scenes/demo_$k.json" --view "$d/views/view_000.json" --out "$tmp/cfg_$k.png" 2>"$tmp/cfg_$k.err" \
    && "$mr" render --scene "$d/scene_$k.json" --view "$d/views/view_000.json" --out "$tmp/glb_$k.png" 2>>"$tmp/cfg_$k.err" \
    && cmp -s "$tmp/cfg_$k.png" "$tmp/glb_$k.png" && ok || bad "configs/scenes/demo_$k.json: not the demo's picture: $(cat "$tmp/cfg_$k.err")"
done
"$mr" replay "$src/recordings/demo" --scene "$src/configs/scenes/demo_planned.json" --out "$tmp/rp_cfg" --from 20 --to 20 \
  >/dev/null 2>"$tmp/rp_cfg.err" && [ -s "$tmp/rp_cfg/overlay_000020.png" ] && ok || bad "replay with the shipped config: $(cat "$tmp/rp_cfg.err") $(ls "$tmp/rp_cfg" 2>&1)"
# A misspelt key is named with the nearest known one; the shipped configs have none.
printf '{"demo": "planned", "hiden": ["Pipe_*"], "lights": [{"direction": [0, 1, 0], "colour": [1, 1, 1]}]}' >"$tmp/typo.json"
"$mr" render --scene "$tmp/typo.json" --view "$d/views/view_000.json" --size 64x48 --out "$tmp/typo.png" 2>"$tmp/typo.err" \
  && grep -q 'unknown key "hiden" (did you mean "hidden"?)' "$tmp/typo.err" \
  && grep -q 'unknown key "colour" (did you mean "color"?)' "$tmp/typo.err" && ok || bad "config typo: $(cat "$tmp/typo.err")"
grep -q "unknown key" "$tmp/cfg_planned.err" "$tmp/cfg_built.err" && bad "shipped configs warn: $(cat "$tmp/cfg_"*.err)" || ok
printf '{"demo": "later"}' >"$tmp/bad_demo.json"
expect_fail bad_demo_config "$tmp/o9.png" -- "$mr" render --scene "$tmp/bad_demo.json" --view "$v" --out "$tmp/o9.png"
expect_fail missing_scene "$tmp/o1.png" -- "$mr" render --scene "$tmp/nope.glb" --view "$v" --out "$tmp/o1.png"
expect_fail missing_view "$tmp/o2.png" -- "$mr" render --scene "$s" --view "$tmp/nope.json" --out "$tmp/o2.png"
head -c 5000 "$d/hall_planned.glb" >"$tmp/trunc.glb"
expect_fail truncated_glb "$tmp/o3.png" -- "$mr" render --scene "$tmp/trunc.glb" --view "$v" --out "$tmp/o3.png"
{ printf 'glTF\002\000\000\000'; head -c 3000 /dev/urandom; } >"$tmp/corrupt.glb"
expect_fail corrupt_glb "$tmp/o4.png" -- "$mr" render --scene "$tmp/corrupt.glb" --view "$v" --out "$tmp/o4.png"
: >"$tmp/empty.glb"
expect_fail empty_file "$tmp/o5.png" -- "$mr" render --scene "$tmp/empty.glb" --view "$v" --out "$tmp/o5.png"

# One triangle, 36 bytes of float positions, as a data URI.
tri_b64=$(printf '\000\000\000\000\000\000\000\000\000\000\000\000\000\000\200\077\000\000\000\000\000\000\000\000\000\000\000\000\000\000\200\077\000\000\000\000' | base64 -w0)
nan_b64=$(printf '\000\000\300\177\000\000\000\000\000\000\000\000\000\000\200\077\000\000\000\000\000\000\000\000\000\000\000\000\000\000\200\077\000\000\000\000' | base64 -w0)
gltf() { # $1 = base64 buffer, $2 = accessor count
  cat <<J
{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
 "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
 "buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,$1"}],
 "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36}],
 "accessors":[{"bufferView":0,"componentType":5126,"count":$2,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}]}
J
}
gltf "$tri_b64" 3 >"$tmp/tri.gltf"
"$mr" render --scene "$tmp/tri.gltf" --view "$v" --out "$tmp/tri.png" 2>"$tmp/tri.err" && ok || bad "valid one-triangle glTF failed: $(cat "$tmp/tri.err")"
gltf "$tri_b64" 100 >"$tmp/range.gltf"
expect_fail accessor_range "$tmp/o6.png" -- "$mr" render --scene "$tmp/range.gltf" --view "$v" --out "$tmp/o6.png"
gltf "$nan_b64" 3 >"$tmp/nan.gltf"
expect_fail nan_position "$tmp/o7.png" -- "$mr" render --scene "$tmp/nan.gltf" --view "$v" --out "$tmp/o7.png"
echo '{"asset": {"version": "2.0"}, "nodes": [' >"$tmp/broken.gltf"
expect_fail broken_json "$tmp/o8.png" -- "$mr" render --scene "$tmp/broken.gltf" --view "$v" --out "$tmp/o8.png"

cam='"camera":{"width":64,"height":48,"fx":0,"fy":50,"cx":32,"cy":24}'
echo "{$cam,\"world_from_camera\":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]}" >"$tmp/zero_f.json"
expect_fail zero_focal "$tmp/o9.png" -- "$mr" render --scene "$s" --view "$tmp/zero_f.json" --out "$tmp/o9.png"
cam='"camera":{"width":64,"height":48,"fx":50,"fy":50,"cx":32,"cy":24}'
echo "{$cam,\"world_from_camera\":[2,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]}" >"$tmp/scaled.json"
expect_fail non_rigid "$tmp/o10.png" -- "$mr" render --scene "$s" --view "$tmp/scaled.json" --out "$tmp/o10.png"
echo "{$cam,\"world_from_camera\":[1,0,0,0,0,1,0,0,0,0,1,0]}" >"$tmp/short.json"
expect_fail short_matrix "$tmp/o11.png" -- "$mr" render --scene "$s" --view "$tmp/short.json" --out "$tmp/o11.png"
expect_fail unwritable "" -- "$mr" render --scene "$s" --view "$v" --out "/nonexistent-dir/x.png"
mkdir -p "$tmp/adir.png"
expect_fail out_is_dir "" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/adir.png"
expect_fail bad_alpha "$tmp/o12.png" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/o12.png" --alpha 1.5
expect_fail bad_size "$tmp/o13.png" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/o13.png" --size 0x10
expect_fail bad_video "$tmp/o14.png" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/o14.png" --video "$tmp/trunc.glb"
expect_fail unknown_option "" -- "$mr" render --frobnicate
expect_fail unknown_command "" -- "$mr" frobnicate
echo '{"gltf": "missing.glb"}' >"$tmp/cfg_missing.json"
expect_fail config_missing_gltf "$tmp/o15.png" -- "$mr" render --scene "$tmp/cfg_missing.json" --view "$v" --out "$tmp/o15.png"
ls "$tmp"/*.tmp.* >/dev/null 2>&1 && bad "temporary files left behind" || ok

# The demo ends with three marks at the known discrepancies and a control
# measurement of an unchanged column, as BCF 2.1 and 3.0 (a topic folder
# each) and the report.
for b in findings.bcf findings-3.0.bcf; do
  n=$(unzip -l "$tmp/demo/$b" 2>/dev/null | grep -cE ' [0-9a-f-]{36}/$')
  [ "$n" = 4 ] && ok || bad "demo: $b has ${n:-no} topic folders, want 4"
done
[ -s "$tmp/demo/report/index.html" ] && [ -s "$tmp/demo/report/img/mark_3_overlay.png" ] && ok || bad "demo: no report"
grep -q "Machine_2" "$tmp/demo/report/index.html" && grep -q "Column_1_0" "$tmp/demo/report/index.html" && ok ||
  bad "demo: the report does not name the discrepancies"
# The marks are placed on frames of the demo's recording at the tracker's
# poses, so each carries the registration's uncertainty and its frame.
ann=$tmp/demo/session/annotations.jsonl
[ "$(grep -c '"uncertainty_m":' "$ann" 2>/dev/null)" = 4 ] && ok || bad "demo: marks without uncertainty_m: $(cat "$ann" 2>&1 | head -c 300)"
[ "$(grep -cE 'recording frame [0-9]+, \+/- [0-9]+ mm' "$tmp/demo.log")" = 4 ] && ok ||
  bad "demo: not four marks on tracked recording frames: $(grep mark "$tmp/demo.log")"
# The moved machine and the control column are measured from several
# recorded frames and judged: the machine's 0.30 m out of tolerance, the
# column within; the report shows both verdicts.
grep -A2 "on Machine_2" "$tmp/demo.log" | grep -Eq "^    verdict: out of tolerance: " && ok ||
  bad "demo: the moved machine is not out of tolerance: $(grep -A2 'on Machine_2' "$tmp/demo.log")"
grep -A2 "control: " "$tmp/demo.log" | grep -Eq "^    verdict: within tolerance: " && ok ||
  bad "demo: the control column is not within tolerance: $(grep -A2 'control: ' "$tmp/demo.log")"
[ "$(grep -c '"verdict":{"verdict":"out"' "$ann")" = 1 ] && [ "$(grep -c '"verdict":{"verdict":"within"' "$ann")" = 1 ] && ok ||
  bad "demo: the marks do not carry the verdicts"
grep -q ">out of tolerance (95 %: " "$tmp/demo/report/index.html" && grep -q ">within tolerance (95 %: " "$tmp/demo/report/index.html" &&
  ok || bad "demo: the report does not show the verdicts"

cli_finish cli_render
