#!/usr/bin/env bash
# The AO and ghosting options as --help prints them from their tables
# (mr_ao_opts, mr_ghost_opts): for each number, a value outside the printed
# range gives one line on stderr naming the option, a non-zero exit and no
# output; the printed bounds themselves are accepted (the command then stops
# at the next check, the missing --scene, so no GPU is needed). Each enum
# refuses an unknown name the same way; replay prints the same rows. The
# tracker's numbers (mr_detector_opts) are walked the same way on track,
# whose rows record prints too.
# Usage: cli_options.sh MRCHECK TMPDIR.
set -u
mr=$1
tmp=$2
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"

"$mr" render --help >"$tmp/help.txt" 2>&1 || bad "render --help failed"
"$mr" replay --help >"$tmp/replay_help.txt" 2>&1 || bad "replay --help failed"
grep -E '^  --(ao|ghost)(-| )' "$tmp/help.txt" >"$tmp/rows.txt"
grep -E '^  --(ao|ghost)(-| )' "$tmp/replay_help.txt" >"$tmp/replay_rows.txt"
cmp -s "$tmp/rows.txt" "$tmp/replay_rows.txt" && ok || bad "render and replay print different AO/ghost rows"

# The command a value is tried on: the refused run (value last) and the
# accepted one, which must stop at the next check (stop_re on stderr).
refuse_cmd=("$mr" render --scene "$tmp/none.glb" --view "$tmp/none.json" --out "$tmp/bad.png")
accept_cmd=("$mr" render --view "$tmp/none.json" --out "$tmp/ok.png")
bad_out=$tmp/bad.png stop_re="are required" what=render

# A value must be refused by its option: one line that names it, no output.
refused() { # NAME VALUE
  local name=$1 value=$2
  rm -f "$bad_out"
  expect_fail "$what-$name=$value" "$bad_out" -- "${refuse_cmd[@]}" "--$name" "$value"
  grep -q -- "--$name " "$tmp/$what-$name=$value.err" && ok || bad "$what --$name $value: the line does not name the option: $(cat "$tmp/$what-$name=$value.err")"
  [ ! -s "$tmp/$what-$name=$value.out" ] && ok || bad "$what --$name $value: printed on stdout"
}
# A value must pass the option table: the command stops at the next check.
accepted() { # NAME VALUE
  local name=$1 value=$2
  [ -n "${accept_cmd[0]:-}" ] || return 0 # benches: an accepted value would run the bench
  "${accept_cmd[@]}" "--$name" "$value" >/dev/null 2>"$tmp/ok.err" && bad "$what --$name $value: ran without its required options"
  grep -q -- "$stop_re" "$tmp/ok.err" && ok || bad "$what --$name $value refused: $(cat "$tmp/ok.err")"
}

# walk_rows FILE: every option row of a help text in FILE; counts numbers and enums.
numbers=0 enums=0
walk_rows() {
  numbers=0 enums=0
  while read -r name arg rest; do
    name=${name#--}
    case $arg in
      N)
        lohi=$(sed -nE 's/.*; (-?[0-9]+)\.\.(-?[0-9]+) \(default.*/\1 \2/p' <<<"$rest")
        [ -n "$lohi" ] || continue # a row of the command's own (--ao-rays, --max-frames)
        read -r lo hi <<<"$lohi"
        refused "$name" $((lo - 1)); refused "$name" $((hi + 1))
        accepted "$name" "$lo"; accepted "$name" "$hi"
        numbers=$((numbers + 1)) ;;
      X)
        lohi=$(sed -nE 's/.*; in \[([^,]+), ([^]]+)\] \(default.*/\1 \2/p' <<<"$rest")
        [ -n "$lohi" ] || { bad "$what --$name: no range in its help line: $rest"; continue; }
        read -r lo hi <<<"$lohi"
        below=$(awk -v v="$lo" 'BEGIN { d = v < 0 ? -v : v; printf "%.17g", v - (d > 1 ? d : 1) }')
        above=$(awk -v v="$hi" 'BEGIN { d = v < 0 ? -v : v; printf "%.17g", v + (d > 1 ? d : 1) }')
        refused "$name" "$below"; refused "$name" "$above"
        accepted "$name" "$lo"; accepted "$name" "$hi"
        numbers=$((numbers + 1)) ;;
      NAME)
        refused "$name" no-such-name
        first=$(sed -nE 's/.*; ([a-z0-9]+)[, ].*\(default.*/\1/p' <<<"$rest")
        [ -n "$first" ] && accepted "$name" "$first" || bad "$what --$name: no names in its help line: $rest"
        enums=$((enums + 1)) ;;
    esac
  done <"$1"
}

walk_rows "$tmp/rows.txt"
# Every table row was seen (17 AO and 9 ghosting rows today, 2 of them flags).
[ $numbers -ge 17 ] && [ $enums -ge 7 ] && ok || bad "only $numbers numeric and $enums named options in render --help"
grep -q -- '--ao-samples N ' "$tmp/rows.txt" && grep -q -- '--ghost-tc-sil X ' "$tmp/rows.txt" && ok ||
  bad "render --help lacks --ao-samples or --ghost-tc-sil"

# The tracker's numbers as track --help prints them from mr_detector_opts
# (rows in the table's form "; lo..hi (default" / "; in [lo, hi] (default");
# record prints the same rows. A refused value stops before the input is
# opened or --out written; an accepted one stops at the missing --input.
"$mr" track --help >"$tmp/track_help.txt" 2>&1 || bad "track --help failed"
"$mr" record --help >"$tmp/record_help.txt" 2>&1 || bad "record --help failed"
table_rows='^  --[a-z-]+ [NX] .*; (-?[0-9]+\.\.-?[0-9]+|in \[[^]]+\]) \(default'
grep -E "$table_rows" "$tmp/track_help.txt" >"$tmp/track_rows.txt"
grep -E "$table_rows" "$tmp/record_help.txt" | grep -v -- '^  --jpeg ' >"$tmp/record_rows.txt"
cmp -s "$tmp/track_rows.txt" "$tmp/record_rows.txt" && ok || bad "track and record print different tracker rows"
refuse_cmd=("$mr" track --input "$tmp/none" --out "$tmp/bad.jsonl")
accept_cmd=("$mr" track --out "$tmp/ok.jsonl")
bad_out=$tmp/bad.jsonl stop_re="--input is required" what=track
walk_rows "$tmp/track_rows.txt"
# decimate, threads, refine-edges and sharpening today.
[ $numbers -ge 4 ] && ok || bad "only $numbers numeric tracker options in track --help"
for row in '--decimate X ' '--threads N ' '--refine-edges N ' '--sharpening X '; do
  grep -q -- "^  $row" "$tmp/track_rows.txt" && ok || bad "track --help lacks the table row '$row'"
done

# Each parsed value reaches the detector: on the shipped recording's first
# 60 frames (frame 53 is the first that sharpening 0 changes) at a fixed
# decimation 2 (the default is adaptive, mr_track.h) a non-default value
# changes the detections, and the default given by hand changes nothing;
# decimation 1 detects otherwise than 2. The user's 0 is "off" (stored as
# -1), not "the default".
rec=$(cd "$(dirname "$0")/.." && pwd)/recordings/demo
detections() { "$mr" track --input "$rec" --max-frames 60 --print-detections "$@" 2>"$tmp/det.err" | md5sum; }
base=$(detections --decimate 2)
[ "$(detections --decimate 1)" != "$base" ] && ok || bad "track --decimate 1 detects the same as 2: the value does not reach the detector"
for pair in "refine-edges 0 1" "sharpening 0 0.25"; do
  read -r name other def <<<"$pair"
  [ "$(detections --decimate 2 "--$name" "$other")" != "$base" ] && ok || bad "track --$name $other detects the same as the default: the value does not reach the detector"
  [ "$(detections --decimate 2 "--$name" "$def")" = "$base" ] && ok || bad "track --$name $def (the default) changes the detections"
done
# The user's 0 is "off", not "the default": --refine-edges 0 still parses.
accepted refine-edges 0

# The benches' numbers (mr_bench_*_opts, lib/bench): each refuses a value
# outside its printed range with one line before it opens a GPU or writes
# anything. (An accepted value would run the bench, so only refusals here;
# test_options walks the same tables in-process, both ways.)
for b in ao frame ghost scene tracking shadows multiview map; do
  "$mr" bench $b --help >"$tmp/bench_$b.txt" 2>&1 || bad "bench $b --help failed"
  grep -E "$table_rows" "$tmp/bench_$b.txt" >"$tmp/bench_${b}_rows.txt"
  refuse_cmd=("$mr" bench "$b" --out "$tmp/bench_$b")
  accept_cmd=() bad_out=$tmp/bench_$b what=bench-$b
  walk_rows "$tmp/bench_${b}_rows.txt"
  [ $numbers -ge 1 ] && ok || bad "bench $b --help prints no table rows"
done

# A flag from a table takes no value.
expect_fail "half=1" "$tmp/bad.png" -- "$mr" render --scene x --view y --out "$tmp/bad.png" --ao-half=1
cli_finish cli_options
