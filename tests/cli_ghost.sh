#!/usr/bin/env bash
# End-to-end checks of ghosted views through the command line: the demo's
# triptychs, `render --ghost MODE` (pass list, the picture changes only
# where hidden structure is), no ghosting pass without hidden structure in
# view, and bad ghost options (one line on stderr, non-zero, no output).
# Usage: cli_ghost.sh MRCHECK TMPDIR. Exit 77 = skipped (no GL device: mrcheck exit 69).
set -u
mr=$1
tmp=$2
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"

demo_or_exit cli_ghost "$mr" "$tmp/demo"
d=$tmp/demo
for c in conflict noconflict; do
  for m in alpha g0 adaptive triptych; do
    [ -s "$d/ghost/${c}_$m.png" ] && ok || bad "demo did not write ghost/${c}_$m.png"
  done
done
s=$d/scene_planned.json
v=$d/views/view_000.json
for m in alpha g0 adaptive; do
  if "$mr" render --scene "$s" --view "$v" --size 160x120 --out "$tmp/$m.png" --ghost "$m" --verbose 2>"$tmp/$m.err"; then
    [ -s "$tmp/$m.png" ] && ok || bad "--ghost $m wrote no PNG"
    grep -q "passes: gbuffer ghost_hidden shade ghost_curvature ghost_importance ghost_g0" "$tmp/$m.err" && ok \
      || bad "--ghost $m pass list: $(cat "$tmp/$m.err")"
  else
    bad "--ghost $m failed: $(cat "$tmp/$m.err")"
  fi
done
grep -q "ghost_emphasis" "$tmp/adaptive.err" && ok || bad "adaptive ran no emphasis pass"
grep -q "ghost_emphasis" "$tmp/g0.err" && bad "g0 ran the emphasis pass" || ok
# Saliency importance with the camera frame: no curvature pass.
"$mr" render --scene "$s" --view "$v" --size 160x120 --out "$tmp/sal.png" --video "$d/frames/frame_000.png" --alpha 0.6 \
  --ghost adaptive --ghost-importance saliency --ghost-saliency gauss --verbose 2>"$tmp/sal.err" \
  && grep -q "passes: gbuffer ghost_hidden shade overlay ghost_importance ghost_g0 ghost_analysis ghost_emphasis;" "$tmp/sal.err" \
  && ok || bad "saliency ghosting with video: $(cat "$tmp/sal.err")"
# --ghost off is the plain picture; so is a view with no hidden structure in
# it (looking out of the hall, away from it): no ghosting pass at all.
"$mr" render --scene "$s" --view "$v" --size 160x120 --out "$tmp/plain.png" 2>/dev/null
"$mr" render --scene "$s" --view "$v" --size 160x120 --out "$tmp/off.png" --ghost off 2>/dev/null \
  && cmp -s "$tmp/plain.png" "$tmp/off.png" && ok || bad "--ghost off differs from no --ghost"
cmp -s "$tmp/plain.png" "$tmp/adaptive.png" && bad "--ghost adaptive changed nothing" || ok
cam=$(sed -n '/"camera"/,/}/p' "$v" | tr -d '\n\t')
echo "{$cam \"world_from_camera\": [-1,0,0,0, 0,-1,0,1.6, 0,0,1,100, 0,0,0,1]}" >"$tmp/away.json"
"$mr" render --scene "$s" --view "$tmp/away.json" --size 160x120 --out "$tmp/away.png" --ghost adaptive --verbose 2>"$tmp/away.err" \
  && grep -q "passes: gbuffer shade;" "$tmp/away.err" && ok || bad "no hidden structure in view: $(cat "$tmp/away.err")"
"$mr" render --scene "$s" --view "$v" --size 160x120 --out "$tmp/hh.png" --ghost adaptive --hide-hidden --verbose 2>"$tmp/hh.err" \
  && grep -q "passes: gbuffer shade;" "$tmp/hh.err" && ok || bad "--hide-hidden still ghosts: $(cat "$tmp/hh.err")"

expect_fail bad_mode "$tmp/b1.png" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b1.png" --ghost sometimes
expect_fail bad_importance "$tmp/b2.png" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b2.png" --ghost g0 --ghost-importance colour
expect_fail bad_saliency "$tmp/b3.png" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b3.png" --ghost g0 --ghost-saliency dog
expect_fail bad_t "$tmp/b4.png" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b4.png" --ghost g0 --ghost-opacity 1.5
expect_fail bad_bench "" -- "$mr" bench ghost --frames 0
# The bench runs end to end and reports the legibility that does not use
# the adaptive stage's own target, with the definitions in the CSV.
"$mr" bench ghost --size 64x48 --frames 1 --out "$tmp/bench" >"$tmp/bench.out" 2>"$tmp/bench.err" \
  && grep -q "^# legibility_edge_transfer: " "$tmp/bench/bench_ghost.csv" \
  && grep -q "^scene,.*,legibility_edge_transfer,.*,cv_saliency_ratio," "$tmp/bench/bench_ghost.csv" \
  && [ -s "$tmp/bench/bench_ghost.svg" ] && ok || bad "bench ghost: $(cat "$tmp/bench.err")"

cli_finish cli_ghost
