#!/usr/bin/env bash
# Batch commands stop cleanly and leave no debris: `replay` on the shipped
# recording, sent SIGINT (and SIGTERM) at a random moment after its first
# overlay, leaves a folder whose replay.jsonl lists exactly the images
# present (each one whole) and says so in one line; a second run into it is
# refused without --force and accepted with it; a run that fails before
# writing (a range past the recording's end) leaves no folder; `track`
# stopped by SIGINT still writes its poses file and a summary; `synth`
# stopped leaves a recording that reads back, every line with its image and
# ground truth, and refuses a second run; `calibrate` stopped says so in
# one line and writes no camera (the map's stop inside its bundle
# adjustment is test_batch_stop's).
# Usage: cli_batch_stop.sh MRCHECK TMPDIR. Without a GL device the replay
# parts are skipped (mrcheck exit 69) and the script ends as a skip (77).
set -u
mr=$1
tmp=$2
src=$(cd "$(dirname "$0")/.." && pwd)
rec=$src/recordings/demo
scene=$src/configs/scenes/demo_planned.json
rm -rf "$tmp" && mkdir -p "$tmp"
. "$(dirname "$0")/common_cli.sh"

# consistent DIR: replay.jsonl parses, every line's image exists and is a
# whole PNG, every overlay_*.png is listed, no temporary file is left.
consistent() {
  python3 - "$1" <<'EOF'
import json, os, sys, struct, zlib
d = sys.argv[1]
lines = open(os.path.join(d, "replay.jsonl")).read().splitlines()
listed = set()
for l in lines:
    o = json.loads(l)
    listed.add(o["image"])
    data = open(os.path.join(d, o["image"]), "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", o["image"] + ": not a PNG"
    assert data[-12:-8] == b"\x00\x00\x00\x00" and data[-8:-4] == b"IEND", o["image"] + ": torn PNG"
present = {f for f in os.listdir(d) if f != "replay.jsonl"}
extra, missing = present - listed, listed - present
assert not extra and not missing, "not listed: %s; missing: %s" % (sorted(extra), sorted(missing))
print(len(lines))
EOF
}

# stop_replay SIG OUT: replay into OUT, SIG after a random delay once the
# first overlay is there; sets rc and n (images listed).
stop_replay() {
  local sig=$1 out=$2
  "$mr" replay "$rec" --scene "$scene" --out "$out" >"$out.out" 2>"$out.err" &
  local pid=$! i
  for i in $(seq 1 1200); do
    ls "$out"/overlay_*.png >/dev/null 2>&1 && break
    kill -0 $pid 2>/dev/null || break
    sleep 0.05
  done
  local delay
  delay=$(awk -v r=$RANDOM 'BEGIN { printf "%.2f", r / 32767 * 1.5 }')
  echo "replay: $sig ${delay}s after the first overlay" >&2
  sleep "$delay"
  kill -s "$sig" $pid 2>/dev/null
  wait $pid
  rc=$?
}

stop_replay INT "$tmp/rp"
if [ $rc -eq $MR_EXIT_NODEVICE ]; then
  skip_part "replay stops (no GL device: $(head -c 300 "$tmp/rp.err"))"
else
  [ $rc -eq 130 ] && ok || bad "replay after SIGINT: exit $rc, not 130: $(cat "$tmp/rp.err")"
  n=$(consistent "$tmp/rp") && ok || bad "replay stopped by SIGINT left an inconsistent folder: $n"
  [ "$(wc -l <"$tmp/rp.err")" -eq 1 ] && grep -q "interrupted after frame .*: $n images and replay.jsonl" "$tmp/rp.err" \
    && ok || bad "replay's summary after SIGINT: $(cat "$tmp/rp.err")"

  # A second run into the folder is refused and touches nothing.
  before=$(ls -l "$tmp/rp" | md5sum)
  expect_fail rerun "" -- "$mr" replay "$rec" --scene "$scene" --out "$tmp/rp" --to 2
  [ "$(ls -l "$tmp/rp" | md5sum)" = "$before" ] && ok || bad "the refused rerun changed the folder"
  grep -q -- "--force" "$tmp/rerun.err" && ok || bad "the refusal does not name --force: $(cat "$tmp/rerun.err")"
  "$mr" replay "$rec" --scene "$scene" --out "$tmp/rp" --to 2 --force >/dev/null 2>"$tmp/force.err" \
    && ok || bad "replay --force: $(cat "$tmp/force.err")"

  stop_replay TERM "$tmp/rp_term"
  [ $rc -eq 143 ] && ok || bad "replay after SIGTERM: exit $rc, not 143: $(cat "$tmp/rp_term.err")"
  n=$(consistent "$tmp/rp_term") && ok || bad "replay stopped by SIGTERM left an inconsistent folder: $n"
fi

# A run that fails before writing leaves no folder (nor its parents).
expect_fail past_end "$tmp/new" -- "$mr" replay "$rec" --scene "$scene" --out "$tmp/new/rp" --from 300
expect_fail no_recording "$tmp/new" -- "$mr" replay "$tmp/none" --scene "$scene" --out "$tmp/new/rp"

# track: SIGINT still writes the poses of the frames done, and the summary.
"$mr" track --input "$rec" --out "$tmp/poses.jsonl" >/dev/null 2>"$tmp/track.err" </dev/null &
pid=$!
sleep 0.$((RANDOM % 9 + 1))
kill -INT $pid 2>/dev/null
wait $pid
rc=$?
if [ $rc -eq 0 ]; then
  # finished before the signal came: the summary and the whole file
  grep -q "^track: [0-9]* frames.*wrote $tmp/poses.jsonl" "$tmp/track.err" && ok || bad "track summary: $(cat "$tmp/track.err")"
elif [ $rc -eq 130 ]; then
  n=$(wc -l <"$tmp/poses.jsonl")
  grep -q "^track: interrupted after $n frames.*wrote $tmp/poses.jsonl" "$tmp/track.err" && ok \
    || bad "track after SIGINT: $n poses; $(cat "$tmp/track.err")"
else
  bad "track after SIGINT: exit $rc: $(cat "$tmp/track.err")"
fi
ls "$tmp"/*.tmp.* "$tmp"/*/*.tmp.* >/dev/null 2>&1 && bad "temporary files left behind" || ok

# catching PID: waits until PID has its SIGINT handler installed (bit 2 of
# SigCgt in /proc), so the signal tests the clean stop, not the default
# action; false if the process ended first.
catching() {
  local i
  for i in $(seq 1 400); do
    local m
    m=$(awk '/^SigCgt:/ { print $2 }' /proc/$1/status 2>/dev/null) || return 1
    [ -n "$m" ] || return 1
    [ $((16#$m & 2)) -ne 0 ] && return 0
    sleep 0.02
  done
  return 1
}

# synth: SIGINT after its first frames leaves a recording whose every line
# has its image and its ground truth, the summary says how many; a second
# run into the folder is refused.
"$mr" synth --out "$tmp/syn" --size 160x120 --frames 500 --motion-blur 1 >/dev/null 2>"$tmp/syn.err" &
pid=$!
for i in $(seq 1 1200); do
  [ -s "$tmp/syn/groundtruth.jsonl" ] && break
  kill -0 $pid 2>/dev/null || break
  sleep 0.05
done
sleep 0.$((RANDOM % 5 + 1))
kill -INT $pid 2>/dev/null
wait $pid
rc=$?
if [ $rc -eq $MR_EXIT_NODEVICE ]; then
  skip_part "synth stops (no GL device: $(head -c 300 "$tmp/syn.err"))"
else
  [ $rc -eq 130 ] && ok || bad "synth after SIGINT: exit $rc, not 130: $(cat "$tmp/syn.err")"
  n=$(wc -l <"$tmp/syn/frames.jsonl")
  [ "$n" -ge 1 ] && [ "$(wc -l <"$tmp/syn/groundtruth.jsonl")" -eq "$n" ] && ok \
    || bad "synth stopped: $n frame lines, $(wc -l <"$tmp/syn/groundtruth.jsonl") ground-truth lines"
  [ "$(ls "$tmp/syn/frames" | grep -vc '\.tmp\.')" -eq "$n" ] && ok || bad "synth stopped: $(ls "$tmp/syn/frames" | wc -l) images for $n lines"
  [ "$(wc -l <"$tmp/syn.err")" -eq 1 ] && grep -q "interrupted after frame .*: $n of 500 frames in $tmp/syn" "$tmp/syn.err" \
    && ok || bad "synth's summary after SIGINT ($n frames): $(cat "$tmp/syn.err")"
  "$mr" track --input "$tmp/syn" --print-detections >"$tmp/syn.det" 2>"$tmp/syn.trk" && [ "$(wc -l <"$tmp/syn.det")" -eq "$n" ] \
    && ok || bad "the stopped recording does not read back: $(cat "$tmp/syn.trk")"
  expect_fail synth_rerun "" -- "$mr" synth --out "$tmp/syn" --frames 2
  grep -q -- "--force" "$tmp/synth_rerun.err" && ok || bad "synth's refusal does not name --force: $(cat "$tmp/synth_rerun.err")"
fi
expect_fail synth_bad_size "$tmp/new" -- "$mr" synth --out "$tmp/new/syn" --size 10x10

# calibrate: SIGINT while it reads a long set of board images ends with one
# line, exit 130 and no camera file.
"$mr" synth --calibration "$tmp/cal" >/dev/null 2>"$tmp/cal.err" && ok || bad "synth --calibration: $(cat "$tmp/cal.err")"
mkdir -p "$tmp/cal/many"
for k in $(seq 100 399); do ln "$tmp/cal/images/board_$(printf %02d $((k % 12))).png" "$tmp/cal/many/b$k.png"; done
"$mr" calibrate --images "$tmp/cal/many" --board "$tmp/cal/board.json" --out "$tmp/cal/cam.json" >"$tmp/calib.out" 2>"$tmp/calib.err" &
pid=$!
catching $pid && sleep 0.3
kill -INT $pid 2>/dev/null
wait $pid
rc=$?
[ $rc -eq 130 ] && ok || bad "calibrate after SIGINT: exit $rc, not 130: $(cat "$tmp/calib.err")"
[ "$(wc -l <"$tmp/calib.err")" -eq 1 ] && grep -q "^mrcheck: calibrate: interrupted after [0-9]* images; nothing written" "$tmp/calib.err" \
  && ok || bad "calibrate's line after SIGINT: $(cat "$tmp/calib.err")"
[ ! -e "$tmp/cal/cam.json" ] && ok || bad "calibrate wrote a camera after SIGINT"

cli_finish cli_batch_stop
