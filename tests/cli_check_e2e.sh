#!/usr/bin/env bash
# The planner's check end to end, under Xvfb, on the synthetic demo hall:
# calibrate the camera from the demo's board images, make a hall folder
# (`mrcheck hall init`: the plan, that camera, the marker map, a tolerance
# table for the machines) with the demo's recording as a session, replay it
# with `mrcheck view HALL --replay SESSION` (the recorded poses) driven by a
# --script as a planner would: mark the moved machine with a typed note,
# measure its edge from two frames, measure an unchanged column's edge from
# several frames; then export BCF 2.1 and 3.0 and the HTML report. Checks: the
# mark's part, category, note and fields; the measured distances (the
# demo's 0.30 m shift, the column's 0); the pin in both snapshot pictures
# within 2 px of where the marked world point projects; the snapshot of the
# overlay is the rendered picture with no UI on it (it matches a headless
# render of the same view but for the pin); the BCF topics and the report.
# Usage: cli_check_e2e.sh MRCHECK TMPDIR. Exit 77 = skipped (no GL device).
set -u
mr=$1
tmp=$2
if [ -z "${DISPLAY:-}" ]; then
  if ! command -v xvfb-run >/dev/null 2>&1; then
    echo "cli_check_e2e: FAILED: no display and Xvfb is not installed (scripts/deps.sh installs it)"
    exit 1
  fi
  exec xvfb-run -a -s "-screen 0 1024x768x24" bash "$0" "$@"
fi
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"
command -v python3 >/dev/null 2>&1 || { echo "cli_check_e2e: FAILED: python3 is missing (scripts/deps.sh installs it)"; exit 1; }
here=$(cd "$(dirname "$0")" && pwd)

demo_or_exit cli_check_e2e "$mr" "$tmp/demo"
d=$tmp/demo

# 1. Calibrate from the board images (the demo renders them with its camera).
"$mr" calibrate --images "$d/calib/images" --board "$d/calib/board.json" --out "$tmp/camera.json" >"$tmp/cal.out" 2>&1 \
  && ok || bad "calibrate: $(tail -2 "$tmp/cal.out")"

# 2. The script: where the parts are in the recorded frames (ground truth).
python3 "$here/e2e_check.py" script "$d" "$tmp" >"$tmp/plan.txt" 2>"$tmp/plan.err" && ok || bad "script: $(cat "$tmp/plan.err")"
cat "$tmp/plan.txt"

# 3. The hall: the plan, the calibrated camera, the marker map and a
#    tolerance table (the machines +-10 mm; the rest DIN 18202), the
#    recording as the session "walk".
echo '{"parts": {"Machine_*": 10}}' >"$tmp/tolerances.json"
"$mr" hall init "$tmp/hall" --scene "$d/scene_planned.json" --camera "$tmp/camera.json" --markers "$d/markers.json" \
  --tolerances "$tmp/tolerances.json" >"$tmp/hall.out" 2>&1 && ok || bad "hall init: $(tail -2 "$tmp/hall.out")"
mkdir -p "$tmp/hall/sessions" && cp -r "$d/recording" "$tmp/hall/sessions/walk" && rm -f "$tmp/hall/sessions/walk/annotations.jsonl"
ln -s hall/sessions/walk "$tmp/session" # where e2e_check.py looks

# 4. The check in the window: the hall gives the plan and the tolerances,
#    the session its frames and poses; the replay is shown through the
#    calibrated camera; the marks go into the session.
if timeout 300 "$mr" view "$tmp/hall" --replay walk --camera "$tmp/hall/camera.json" \
     --config "$tmp/cfg.json" --size 800x600 --paused --script "$tmp/check.script" \
     >"$tmp/view.out" 2>"$tmp/view.err"; then ok
else bad "view: $(tail -3 "$tmp/view.err")"; fi
[ -s "$tmp/hall/sessions/walk/annotations.jsonl" ] && ok || bad "view HALL did not write its marks into the session"

# 5. The findings leave the tablet.
"$mr" export "$tmp/hall" walk --bcf "$tmp/findings.bcf" >/dev/null 2>"$tmp/bcf.err" && ok || bad "export --bcf: $(cat "$tmp/bcf.err")"
"$mr" export "$tmp/hall" walk --bcf "$tmp/findings-3.0.bcf" --bcf-version 3.0 >/dev/null 2>"$tmp/bcf3.err" && ok \
  || bad "export --bcf 3.0: $(cat "$tmp/bcf3.err")"
"$mr" export "$tmp/hall" walk --html "$tmp/report" >/dev/null 2>"$tmp/html.err" && ok \
  || bad "export --html: $(cat "$tmp/html.err")"
grep -q "<rect x=" "$tmp/report/index.html" && ok || bad "the report's plan view has no parts: the hall's scene did not reach export"

# 6. The checks on what was written (e2e_check.py check prints one line per
#    failure and "ok N" for the passes).
python3 "$here/e2e_check.py" check "$d" "$tmp" "$mr" >"$tmp/check.txt" 2>&1 || true
while IFS= read -r line; do
  case $line in
    "ok "*) for _ in $(seq 1 "${line#ok }"); do ok; done ;;
    "info: "*) echo "$line" ;;
    *) bad "$line" ;;
  esac
done <"$tmp/check.txt"
grep -q "^ok " "$tmp/check.txt" || bad "the checks did not run: $(tail -3 "$tmp/check.txt")"

cli_finish cli_check_e2e
