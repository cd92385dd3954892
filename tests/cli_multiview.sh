#!/usr/bin/env bash
# Multi-view output of `mrcheck render` and `mrcheck replay` (--views,
# --quilt): the files and their names, the quilt's size, and bad input (one
# line, non-zero exit, nothing written). The rig's maths is test_multiview's.
# Usage: cli_multiview.sh MRCHECK TMPDIR. Exit 77 = skipped (no GL device).
set -u
mr=$1
tmp=$2
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"
src=$(cd "$(dirname "$0")/.." && pwd)
s=$src/configs/scenes/demo_planned.json
# The shipped scene config builds the demo hall itself; a shipped view.
v=$src/configs/views/demo_partition.json

# PNG width and height from the IHDR chunk.
png_size() { od -An -tu1 -j16 -N8 "$1" | awk '{print $1*16777216+$2*65536+$3*256+$4 "x" $5*16777216+$6*65536+$7*256+$8}'; }

# 8 views of 64x48: view_000..007 and an about-square 3x3 quilt.
"$mr" render --scene "$s" --view "$v" --out "$tmp/mv" --views 8 --size 64x48 --ao crytek >"$tmp/mv.log" 2>&1
rc=$?
[ $rc -eq $MR_EXIT_NODEVICE ] && { echo "cli_multiview: SKIPPED: no GL device: $(cat "$tmp/mv.log")"; exit 77; }
if [ $rc -eq 0 ]; then
  n=$(ls "$tmp/mv"/view_*.png 2>/dev/null | wc -l)
  [ "$n" -eq 8 ] && [ -s "$tmp/mv/view_000.png" ] && [ -s "$tmp/mv/view_007.png" ] && ok || bad "expected 8 view PNGs, got $n"
  [ "$(png_size "$tmp/mv/view_003.png")" = "64x48" ] && ok || bad "view size $(png_size "$tmp/mv/view_003.png")"
  [ -s "$tmp/mv/quilt_qs3x3a1.333.png" ] && [ "$(png_size "$tmp/mv/quilt_qs3x3a1.333.png")" = "192x144" ] && ok \
    || bad "quilt missing or wrong size: $(ls "$tmp/mv")"
  cmp -s "$tmp/mv/view_000.png" "$tmp/mv/view_007.png" && bad "view 0 and view 7 are the same picture" || ok
else
  bad "render --views failed (exit $rc): $(cat "$tmp/mv.log")"
fi
# A quilt cut from a given size: tiles 32x24, the name carries the view aspect.
"$mr" render --scene "$s" --view "$v" --out "$tmp/q" --quilt "4x2@128x48" --focal-distance 3 >"$tmp/q.log" 2>&1 \
  && [ "$(png_size "$tmp/q/quilt_qs4x2a1.333.png")" = "128x48" ] && [ "$(png_size "$tmp/q/view_007.png")" = "32x24" ] \
  && ok || bad "--quilt 4x2@128x48: $(cat "$tmp/q.log") $(ls "$tmp/q" 2>&1)"
# The same command twice gives the same files.
"$mr" render --scene "$s" --view "$v" --out "$tmp/q2" --quilt "4x2@128x48" --focal-distance 3 >/dev/null 2>&1 \
  && cmp -s "$tmp/q/quilt_qs4x2a1.333.png" "$tmp/q2/quilt_qs4x2a1.333.png" && ok || bad "quilt not reproducible"
# Without --views: one image as before, not a folder.
"$mr" render --scene "$s" --view "$v" --out "$tmp/one.png" --size 64x48 >/dev/null 2>&1 && [ -f "$tmp/one.png" ] && ok \
  || bad "plain render"

# Replay: per frame a quilt and a folder of views; the log names the quilt.
if "$mr" replay "$src/recordings/demo" --scene "$s" --out "$tmp/rp" --from 40 --to 41 --views 4 --quilt 2x2 \
     --focal-distance 3 >"$tmp/rp.log" 2>&1; then
  [ -s "$tmp/rp/overlay_000040_qs2x2a1.333.png" ] && [ -s "$tmp/rp/overlay_000041_qs2x2a1.333.png" ] && ok \
    || bad "replay quilts missing: $(ls "$tmp/rp")"
  [ "$(ls "$tmp/rp/overlay_000040"/view_*.png | wc -l)" -eq 4 ] && ok || bad "replay views missing"
  grep -q '"image":"overlay_000040_qs2x2a1.333.png"' "$tmp/rp/replay.jsonl" && ok || bad "replay.jsonl: $(head -c 300 "$tmp/rp/replay.jsonl")"
else
  rc=$?
  need_device $rc "$tmp/rp.log" "replay --views"
fi

# One image under the light-field display mapping, exact (band 1) and in
# slices of 8 columns: both a picture, not the same one.
"$mr" render --scene "$s" --view "$v" --out "$tmp/lf1.png" --lightfield 1 --size 64x48 --ao filion >"$tmp/lf.log" 2>&1 \
  && "$mr" render --scene "$s" --view "$v" --out "$tmp/lf8.png" --lightfield 8 --size 64x48 --ao filion >>"$tmp/lf.log" 2>&1 \
  && [ "$(png_size "$tmp/lf1.png")" = "64x48" ] && ! cmp -s "$tmp/lf1.png" "$tmp/lf8.png" && ok \
  || bad "--lightfield: $(cat "$tmp/lf.log")"

# --- bad input -----------------------------------------------------------
expect_fail lf0 "$tmp/b12.png" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b12.png" --lightfield 0
expect_fail lf_views "$tmp/b13" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b13" --lightfield 1 --views 4
expect_fail views0 "$tmp/b1" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b1" --views 0
expect_fail views_neg "$tmp/b2" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b2" --views -3
expect_fail cone180 "$tmp/b3" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b3" --views 8 --view-cone 180
expect_fail quilt_small "$tmp/b4" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b4" --views 8 --quilt 2x2 --size 64x48
expect_fail quilt_bad "$tmp/b5" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b5" --views 8 --quilt 8by6
expect_fail quilt_tiny "$tmp/b6" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b6" --quilt 8x6@4x4
expect_fail cone_alone "$tmp/b7" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b7.png" --view-cone 20
expect_fail focal_neg "$tmp/b8" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b8" --views 4 --focal-distance -1
expect_fail views_aux "$tmp/b9" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b9" --views 4 --aux "$tmp/b9aux"
expect_fail replay_lf "$tmp/b14" -- "$mr" replay "$src/recordings/demo" --scene "$s" --out "$tmp/b14" --lightfield 1
expect_fail replay_views0 "$tmp/b10" -- "$mr" replay "$src/recordings/demo" --scene "$s" --out "$tmp/b10" --views 0
expect_fail replay_quilt_small "$tmp/b11" -- "$mr" replay "$src/recordings/demo" --scene "$s" --out "$tmp/b11/x" --from 20 --to 20 --views 5 --quilt 2x2

cli_finish cli_multiview
