#!/usr/bin/env bash
# Every command's --help: exit 0 and the options a planner uses before the
# research settings, which stand under their own heading ("research
# options:"): the view's files and folders above its AO and ghosting
# start modes and test script, render's and replay's files above the AO,
# ghosting, shadow and draw tables, track's input above the detector's
# tuning, map's photos and gauge above the adjustment's tuning, calibrate's
# and measure's inputs above theirs, synth's output above its sensor model.
# A command that takes a hall says so.
# Usage: cli_help.sh MRCHECK TMPDIR.
set -u
mr=$1
tmp=$2
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"

cmds=$("$mr" --help | sed -n 's/^  \([a-z]*\) .*/\1/p')
[ "$(echo "$cmds" | wc -w)" -ge 10 ] && ok || bad "mrcheck --help lists only: $cmds"
for c in $cmds; do
  case $c in bench|study) continue ;; esac
  "$mr" "$c" --help >"$tmp/$c.txt" 2>"$tmp/$c.err" && [ -s "$tmp/$c.txt" ] && ok || bad "mrcheck $c --help failed: $(cat "$tmp/$c.err")"
done
# line FILE OPTION: the line number of an option's row (0 if none).
line() { grep -n -- "^  --$2[ ]" "$1" | head -1 | cut -d: -f1 | grep . || echo 0; }
heading() { grep -n '^research options:$' "$1" | head -1 | cut -d: -f1 | grep . || echo 0; }
# order CMD "PLANNER..." "RESEARCH...": each planner option above the heading,
# each research one below it.
order() {
  local c=$1 h
  h=$(heading "$tmp/$c.txt")
  [ "$h" -gt 0 ] && ok || { bad "$c --help has no research heading"; return; }
  for o in $2; do
    l=$(line "$tmp/$c.txt" "$o")
    [ "$l" -gt 0 ] && [ "$l" -lt "$h" ] && ok || bad "$c --help: --$o (line $l) is not among the planner's options (heading at $h)"
  done
  for o in $3; do
    l=$(line "$tmp/$c.txt" "$o")
    [ "$l" -gt "$h" ] && ok || bad "$c --help: --$o (line $l) is not under the research heading (line $h)"
  done
}
order view "scene input camera markers replay out size paused" "ao ghost script stats retrack shadows"
order render "scene view out size video" "ao ao-samples ghost ghost-opacity shadows shadows-taps lod cull views quilt aux"
order replay "scene out video from to every" "ao ghost shadows lod views"
order track "input camera markers out" "decimate threads"
order map "images video camera tag-size tag-sizes fix control out" "loss refine-intrinsics chain"
order calibrate "images board out" "min-tags"
order measure "recording observations scene tolerances" "tap-sigma min-angle"
order synth "out size frames" "noise motion-blur shutter exposure jpeg"
for c in view replay map calibrate measure export render record track; do
  grep -q '^hall (`mrcheck '"$c"' HALL' "$tmp/$c.txt" && ok || bad "$c --help does not say it takes a hall"
done
cli_finish cli_help
