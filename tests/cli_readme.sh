#!/usr/bin/env bash
# The README's commands run as written after its first command: `mrcheck
# demo` (here into a scratch copy of the repository's layout), then every
# line of its ```sh blocks in order, except the Quick start's build and
# test lines and those marked "on the tablet" (a live camera). A view runs
# under Xvfb with a script that quits. Then the hall the steps made names
# the camera, control points and marker map, and every file of it loads.
# Usage: cli_readme.sh MRCHECK TMPDIR. Exit 77 = skipped (no Xvfb / no GL).
set -u
mr=$1
tmp=$2
if [ -z "${DISPLAY:-}" ]; then
  if ! command -v xvfb-run >/dev/null 2>&1; then
    echo "cli_readme: SKIPPED: no display and Xvfb is not installed (apt-get install xvfb xauth)"
    exit 77
  fi
  exec xvfb-run -a -s "-screen 0 1024x768x24" bash "$0" "$@"
fi
case $mr in /*) ;; *) mr=$PWD/$mr ;; esac
src=$(cd "$(dirname "$0")/.." && pwd)
rm -rf "$tmp" && mkdir -p "$tmp/repo/build"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"
ln -s "$mr" "$tmp/repo/build/mrcheck"
ln -s "$src/configs" "$tmp/repo/configs"
ln -s "$src/recordings" "$tmp/repo/recordings"
cd "$tmp/repo" || exit 1
# The README's code lines, continuation lines joined, comments dropped.
python3 - "$src/README.md" >"$tmp/lines.txt" <<'PY'
import re, sys
text = open(sys.argv[1], encoding="utf-8").read()
for block in re.findall(r"```sh\n(.*?)```", text, re.S):
    for line in block.replace("\\\n", " ").splitlines():
        if "on the tablet" in line or not line.strip() or line.strip().startswith("#"):
            continue
        print(line.split(" #")[0].strip())
PY
[ "$(wc -l <"$tmp/lines.txt")" -ge 12 ] && ok || bad "only $(wc -l <"$tmp/lines.txt") command lines found in the README"
first=$(head -1 "$tmp/lines.txt")
[ "$first" = "bash scripts/build.sh && ./build/mrcheck demo" ] && ok || bad "the README's first command is '$first'"
"$mr" demo >"$tmp/demo.log" 2>&1
need_device $? "$tmp/demo.log" "mrcheck demo" || cli_finish cli_readme
printf '%s\n' "0.5 quit" >"$tmp/quit.script"
n=0
while IFS= read -r line; do
  n=$((n + 1))
  case $line in
    "bash scripts/"*) continue ;;  # the Quick start's build and test suite
    ./build/mrcheck\ view\ *) line="$line --script $tmp/quit.script --config $tmp/view.json --size 480x360" ;;
  esac
  if timeout 300 bash -c "$line" >"$tmp/line$n.out" 2>&1; then ok
  else bad "README line $n failed: $line: $(tail -3 "$tmp/line$n.out")"; fi
done <"$tmp/lines.txt"
# The hall the steps made.
for k in scene camera control markers; do
  grep -q "\"$k\":" my-hall/hall.json && ok || bad "my-hall/hall.json does not name its $k: $(cat my-hall/hall.json)"
done
"$mr" hall show my-hall >"$tmp/show.out" 2>&1 && ok || bad "hall show my-hall: $(cat "$tmp/show.out")"
[ -s findings.bcf ] && [ -s report/index.html ] && ok || bad "the README's export wrote no BCF or report"
cli_finish cli_readme
