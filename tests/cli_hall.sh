#!/usr/bin/env bash
# The hall folder on the command line: `hall init` checks each file (a bad
# one: one line, non-zero exit, no folder), the manifest's paths work from
# another working directory, an unknown key is warned about with the
# nearest known one, and `view HALL --replay SESSION` (scripted, under
# Xvfb) needs no other flag and writes its marks inside the hall, also for
# a recording that lies outside it (which stays untouched).
# Usage: cli_hall.sh MRCHECK TMPDIR. Exit 77 = skipped (no Xvfb / no GL).
set -u
mr=$1
tmp=$2
if [ -z "${DISPLAY:-}" ]; then
  if ! command -v xvfb-run >/dev/null 2>&1; then
    echo "cli_hall: SKIPPED: no display and Xvfb is not installed (apt-get install xvfb xauth)"
    exit 77
  fi
  exec xvfb-run -a -s "-screen 0 1024x768x24" bash "$0" "$@"
fi
case $mr in /*) ;; *) mr=$PWD/$mr ;; esac
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"
src=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$tmp/a/plan" "$tmp/b/c"
cp "$src/configs/scenes/demo_planned.json" "$tmp/a/plan/"
cp "$src/configs/cameras/demo_640x480.json" "$tmp/a/camera.json"
cp "$src/configs/markers/demo_hall.json" "$tmp/a/markers.json"
printf '{"default_mm": 20, "parts": {"Machine_*": 5}}\n' >"$tmp/a/tol.json"
printf '{"points": [{"name": "P1", "tag": 0, "xyz": [0, 0, 0]}, {"name": "P2", "tag": 1, "xyz": [1, 0, 0]}, {"name": "P3", "tag": 2, "xyz": [0, 1, 0]}]}\n' >"$tmp/a/control.json"
printf '{"default_mm": -5}\n' >"$tmp/a/bad_tol.json"
printf '{"points": "none"}\n' >"$tmp/a/bad_control.json"
cd "$tmp/a" || exit 1

# 1. Each bad file: one line naming it, non-zero, and no hall folder.
good="--scene plan/demo_planned.json --camera camera.json"
expect_fail bad_scene "$tmp/a/h" -- "$mr" hall init h --scene "$src/README.md"
grep -q "README.md" "$tmp/bad_scene.err" && ok || bad "bad scene: the line does not name the file: $(cat "$tmp/bad_scene.err")"
expect_fail bad_camera "$tmp/a/h" -- "$mr" hall init h --scene plan/demo_planned.json --camera markers.json
grep -q "markers.json" "$tmp/bad_camera.err" && ok || bad "bad camera: $(cat "$tmp/bad_camera.err")"
# shellcheck disable=SC2086
expect_fail bad_markers "$tmp/a/h" -- "$mr" hall init h $good --markers camera.json
# shellcheck disable=SC2086
expect_fail bad_control "$tmp/a/h" -- "$mr" hall init h $good --control bad_control.json
# shellcheck disable=SC2086
expect_fail bad_tolerances "$tmp/a/h" -- "$mr" hall init h $good --tolerances bad_tol.json
# shellcheck disable=SC2086
expect_fail missing_file "$tmp/a/h" -- "$mr" hall init h $good --markers nowhere.json
expect_fail no_plan "$tmp/a/h" -- "$mr" hall init h --camera camera.json
expect_fail add_no_hall "$tmp/a/nohall" -- "$mr" hall add nohall --camera camera.json

# 2. Good files, given relative to this folder; then from another one.
# shellcheck disable=SC2086
if "$mr" hall init h $good --markers markers.json --control control.json --tolerances tol.json >"$tmp/init.out" 2>"$tmp/init.err"; then
  ok
  [ -s h/hall.json ] && [ -s h/camera.json ] && [ -s h/markers.json ] && [ -s h/control.json ] && [ -s h/tolerances.json ] \
    && ok || bad "hall init did not write the manifest and copies: $(ls h)"
  grep -q '"scene":[[:space:]]*"../plan/demo_planned.json"' h/hall.json && ok || bad "the plan is not named relative to the hall: $(cat h/hall.json)"
else
  bad "hall init with good files failed: $(cat "$tmp/init.err")"
fi
(cd "$tmp/b/c" && "$mr" hall show ../../a/h >"$tmp/show.out" 2>"$tmp/show.err") && ok \
  || bad "hall show from another folder failed: $(cat "$tmp/show.out" "$tmp/show.err")"
[ "$(grep -c ': ok$' "$tmp/show.out")" -eq 5 ] && ok || bad "hall show: not all five files load: $(cat "$tmp/show.out")"
# Replacing a file with a bad one leaves the hall as it was.
cp h/hall.json "$tmp/manifest.before"
expect_fail add_bad "" -- "$mr" hall add h --camera markers.json
cmp -s h/hall.json "$tmp/manifest.before" && cmp -s h/camera.json camera.json && ok || bad "a refused add changed the hall"

# 3. An unknown key: a warning naming it and the nearest known key.
sed 's/"sessions"/"camra": "x.json", "sessions"/' "$tmp/manifest.before" >h/hall.json
"$mr" hall show h >/dev/null 2>"$tmp/unknown.err"
grep -q 'unknown key "camra" (did you mean "camera"?)' "$tmp/unknown.err" && ok || bad "no warning for an unknown key: $(cat "$tmp/unknown.err")"
cp "$tmp/manifest.before" h/hall.json

# 4. view HALL --replay SESSION, scripted: a mark, written inside the hall.
#    The session by its name in HALL/sessions/, and a recording outside the
#    hall (the shipped one), whose folder must stay as it was.
mkdir -p h/sessions
cp -r "$src/recordings/demo" h/sessions/walk
rm -f h/sessions/walk/annotations.jsonl
ls -la "$src/recordings/demo" >"$tmp/shipped.before"
printf '%s\n' "0.2 key ." "0.6 key ." "0.7 frame 2" "1.4 tap @mark" "1.8 tap 150 150" "2.4 tap @note2" "3.5 quit" >"$tmp/mark.script"
for session in walk "$src/recordings/demo"; do
  name=$(basename "$session")
  (cd "$tmp/b/c" && timeout 120 "$mr" view ../../a/h --replay "$session" --config "$tmp/cfg.json" --size 480x360 --paused \
     --script "$tmp/mark.script" >"$tmp/view_$name.out" 2>"$tmp/view_$name.err")
  rc=$?
  if need_device $rc "$tmp/view_$name.err" "view HALL --replay $name"; then
    ann=h/sessions/$name/annotations.jsonl
    if [ -s "$ann" ] && grep -q '"category":"extra"' "$ann" && grep -q '"snapshot":{' "$ann"; then ok
    else bad "view HALL --replay $name: no mark in $ann: $(tail -3 "$tmp/view_$name.err")"; fi
    snap=$(sed -n 's/.*"screen":"\([^"]*\)".*/\1/p' "$ann" | head -1)
    [ -n "$snap" ] && [ -s "h/sessions/$name/$snap" ] && ok || bad "view HALL: the mark's snapshot is not in the hall ($snap)"
  fi
done
ls -la "$src/recordings/demo" >"$tmp/shipped.after"
cmp -s "$tmp/shipped.before" "$tmp/shipped.after" && ok || bad "view HALL wrote into the shipped recording"
cli_finish cli_hall
