#!/usr/bin/env bash
# The AO and ghosting options as --help prints them from their tables
# (mr_ao_opts, mr_ghost_opts): for each number, a value outside the printed
# range gives one line on stderr naming the option, a non-zero exit and no
# output; the printed bounds themselves are accepted (the command then stops
# at the next check, the missing --scene, so no GPU is needed). Each enum
# refuses an unknown name the same way; replay prints the same rows.
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

# A value must be refused by its option: one line that names it.
refused() { # NAME VALUE
  local name=$1 value=$2
  rm -f "$tmp/bad.png"
  expect_fail "$name=$value" "$tmp/bad.png" -- "$mr" render --scene "$tmp/none.glb" --view "$tmp/none.json" \
    --out "$tmp/bad.png" "--$name" "$value"
  grep -q -- "--$name " "$tmp/$name=$value.err" && ok || bad "--$name $value: the line does not name the option: $(cat "$tmp/$name=$value.err")"
}
# A value must pass the option table: the command stops at the missing --scene.
accepted() { # NAME VALUE
  local name=$1 value=$2
  "$mr" render --view "$tmp/none.json" --out "$tmp/ok.png" "--$name" "$value" 2>"$tmp/ok.err" && bad "--$name $value: ran without --scene"
  grep -q "are required" "$tmp/ok.err" && ok || bad "--$name $value refused: $(cat "$tmp/ok.err")"
}

numbers=0 enums=0
while read -r name arg rest; do
  name=${name#--}
  case $arg in
    N)
      lohi=$(sed -nE 's/.*; (-?[0-9]+)\.\.(-?[0-9]+) \(default.*/\1 \2/p' <<<"$rest")
      [ -n "$lohi" ] || continue # a row of the command's own (--ao-rays)
      read -r lo hi <<<"$lohi"
      refused "$name" $((lo - 1)); refused "$name" $((hi + 1))
      accepted "$name" "$lo"; accepted "$name" "$hi"
      numbers=$((numbers + 1)) ;;
    X)
      lohi=$(sed -nE 's/.*; in \[([^,]+), ([^]]+)\] \(default.*/\1 \2/p' <<<"$rest")
      [ -n "$lohi" ] || { bad "--$name: no range in its help line: $rest"; continue; }
      read -r lo hi <<<"$lohi"
      below=$(awk -v v="$lo" 'BEGIN { d = v < 0 ? -v : v; printf "%.17g", v - (d > 1 ? d : 1) }')
      above=$(awk -v v="$hi" 'BEGIN { d = v < 0 ? -v : v; printf "%.17g", v + (d > 1 ? d : 1) }')
      refused "$name" "$below"; refused "$name" "$above"
      accepted "$name" "$lo"; accepted "$name" "$hi"
      numbers=$((numbers + 1)) ;;
    NAME)
      refused "$name" no-such-name
      first=$(sed -nE 's/.*; ([a-z0-9]+)[, ].*\(default.*/\1/p' <<<"$rest")
      [ -n "$first" ] && accepted "$name" "$first" || bad "--$name: no names in its help line: $rest"
      enums=$((enums + 1)) ;;
  esac
done <"$tmp/rows.txt"
# Every table row was seen (17 AO and 9 ghosting rows today, 2 of them flags).
[ $numbers -ge 17 ] && [ $enums -ge 7 ] && ok || bad "only $numbers numeric and $enums named options in render --help"
grep -q -- '--ao-samples N ' "$tmp/rows.txt" && grep -q -- '--ghost-tc-sil X ' "$tmp/rows.txt" && ok ||
  bad "render --help lacks --ao-samples or --ghost-tc-sil"
# A flag from a table takes no value.
expect_fail "half=1" "$tmp/bad.png" -- "$mr" render --scene x --view y --out "$tmp/bad.png" --ao-half=1
cli_finish cli_options
