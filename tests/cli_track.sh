#!/usr/bin/env bash
# End-to-end checks of track, record (incl. kill -9 mid-record), replay,
# calibrate, synth and bench tracking on the shipped recording, and of bad
# input: one line on stderr, a non-zero exit, no output file left behind.
# Usage: cli_track.sh MRCHECK TMPDIR. Parts that need a GL device are skipped
# without one (mrcheck exit 69), and the script then ends as a skip (77).
set -u
mr=$1
tmp=$2
src=$(cd "$(dirname "$0")/.." && pwd)
rec=$src/recordings/demo
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"
nframes=$(wc -l <"$rec/frames.jsonl")

# --- track ---------------------------------------------------------------
"$mr" track --input "$rec" --print-detections >"$tmp/det.jsonl" 2>"$tmp/det.err" && ok || bad "track --print-detections failed: $(cat "$tmp/det.err")"
[ "$(wc -l <"$tmp/det.jsonl")" -eq "$nframes" ] && ok || bad "track printed $(wc -l <"$tmp/det.jsonl") lines for $nframes frames"
grep -q '^{"frame":0,"detections":\[{"id":16,"hamming":0,"corners":\[\[' "$tmp/det.jsonl" && ok || bad "detection line format: $(head -c 200 "$tmp/det.jsonl")"
"$mr" track --input "$rec" --out "$tmp/poses.jsonl" 2>"$tmp/poses.err" && ok || bad "track --out failed: $(cat "$tmp/poses.err")"
[ "$(grep -c '"valid":true' "$tmp/poses.jsonl")" -ge $((nframes / 2)) ] && ok || bad "fewer than half the frames have a pose"
grep -q '"world_from_camera":\[' "$tmp/poses.jsonl" && grep -q '"filtered":\[' "$tmp/poses.jsonl" && ok || bad "pose lines lack matrices"
# Same input, same output.
"$mr" track --input "$rec" --out "$tmp/poses2.jsonl" 2>/dev/null && cmp -s "$tmp/poses.jsonl" "$tmp/poses2.jsonl" && ok || bad "track is not deterministic"
# --freeze: one filtered pose for the whole run (a still-image check).
"$mr" track --input "$rec" --freeze --out "$tmp/frozen.jsonl" 2>/dev/null && ok || bad "track --freeze failed"
[ "$(grep -o '"filtered":\[[^]]*\]' "$tmp/frozen.jsonl" | sort -u | wc -l)" -eq 1 ] && ok || bad "--freeze: the filtered pose changed"
[ "$(grep -c '"filtered"' "$tmp/frozen.jsonl")" -gt "$(grep -c '"valid":true' "$tmp/frozen.jsonl")" ] && ok || bad "--freeze: no held pose on frames without tags"
# Explicit camera and markers from the recording's meta, on an image folder.
"$mr" track --input "$rec/frames" --camera "$src/configs/cameras/demo_640x480.json" --markers "$src/configs/markers/demo_hall.json" \
  --decimate 1 --threads 2 --refine-edges 0 --family tag36h11 --max-frames 5 >"$tmp/folder.jsonl" 2>"$tmp/folder.err" \
  && [ "$(wc -l <"$tmp/folder.jsonl")" -eq 5 ] && ok || bad "track on a folder with options: $(cat "$tmp/folder.err")"

# --- bad input -------------------------------------------------------------
expect_fail no_device "$tmp/o1.jsonl" -- "$mr" track --input /dev/video99 --out "$tmp/o1.jsonl"
grep -q "no such device" "$tmp/no_device.err" && ok || bad "no such device message: $(cat "$tmp/no_device.err")"
expect_fail not_v4l2 "" -- "$mr" track --input /dev/null
head -c 4000 /dev/urandom >"$tmp/corrupt.mp4"
expect_fail corrupt_video "" -- "$mr" track --input "$tmp/corrupt.mp4"
: >"$tmp/empty.mp4"
expect_fail empty_video "" -- "$mr" track --input "$tmp/empty.mp4"
echo iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAAAAAA6fptVAAAACklEQVR4nGNgAAAAAgABSK+kcQAAAABJRU5ErkJggg== | base64 -d >"$tmp/one.png"
expect_fail tiny_frame "" -- "$mr" track --input "$tmp/one.png" --print-detections
grep -q "too small" "$tmp/tiny_frame.err" && ok || bad "tiny frame message: $(cat "$tmp/tiny_frame.err")"
expect_fail missing_input "" -- "$mr" track --input "$tmp/nope.mp4"
expect_fail no_input "" -- "$mr" track
expect_fail bad_decimate "" -- "$mr" track --input "$rec" --decimate 0.5
expect_fail bad_family "" -- "$mr" track --input "$rec" --family tag99h1
ident='[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]'
echo "{\"family\":\"tag36h11\",\"tag_size\":0.4,\"tags\":[{\"id\":1,\"world_from_tag\":$ident},{\"id\":1,\"world_from_tag\":$ident}]}" >"$tmp/dup.json"
expect_fail duplicate_ids "$tmp/o2.jsonl" -- "$mr" track --input "$rec" --markers "$tmp/dup.json" --out "$tmp/o2.jsonl"
grep -q "duplicate" "$tmp/duplicate_ids.err" && ok || bad "duplicate id message"
echo "{\"family\":\"tag36h11\",\"tag_size\":0,\"tags\":[{\"id\":1,\"world_from_tag\":$ident}]}" >"$tmp/size0.json"
expect_fail tag_size_zero "$tmp/o3.jsonl" -- "$mr" track --input "$rec" --markers "$tmp/size0.json" --out "$tmp/o3.jsonl"
echo '{"width":640,"height":480,"fx":0,"fy":500,"cx":320,"cy":240}' >"$tmp/f0.json"
expect_fail zero_focal "$tmp/o4.jsonl" -- "$mr" track --input "$rec" --camera "$tmp/f0.json" --out "$tmp/o4.jsonl"
expect_fail out_needs_pose "$tmp/o5.jsonl" -- "$mr" track --input "$rec/frames" --out "$tmp/o5.jsonl"

# A recording with a garbage line and a torn last line: warns, goes on.
cp -r "$rec" "$tmp/damaged"
{ head -n 5 "$rec/frames.jsonl"; echo 'garbage {{{'; sed -n '6,$p' "$rec/frames.jsonl"; printf '{"frame":999,"t":9'; } >"$tmp/damaged/frames.jsonl"
"$mr" track --input "$tmp/damaged" --print-detections >"$tmp/damaged.out" 2>"$tmp/damaged.err" && ok || bad "damaged recording: $(cat "$tmp/damaged.err")"
[ "$(wc -l <"$tmp/damaged.out")" -eq "$nframes" ] && ok || bad "damaged recording: $(wc -l <"$tmp/damaged.out") frames"
grep -q "skipped 1 unreadable line" "$tmp/damaged.err" && ok || bad "no warning for the garbage line: $(cat "$tmp/damaged.err")"

# --- record, and kill -9 in the middle -----------------------------------
"$mr" record --input "$rec" --out "$tmp/rec1" --max-frames 12 >"$tmp/rec1.out" 2>"$tmp/rec1.err" && ok || bad "record failed: $(cat "$tmp/rec1.err")"
[ "$(wc -l <"$tmp/rec1/frames.jsonl")" -eq 12 ] && [ -s "$tmp/rec1/frames/000011.jpg" ] && [ -s "$tmp/rec1/meta.json" ] && ok || bad "record wrote the wrong files"
expect_fail record_exists "" -- "$mr" record --input "$rec" --out "$tmp/rec1" --max-frames 2
[ "$(wc -l <"$tmp/rec1/frames.jsonl")" -eq 12 ] && ok || bad "an existing recording was touched"
expect_fail record_needs_camera "" -- "$mr" record --input "$rec/frames" --out "$tmp/rec2"

"$mr" record --input "$rec" --out "$tmp/killed" --rate 25 >/dev/null 2>&1 &
pid=$!
# Killed mid-run once a few frames are in (a loaded machine is slow to start).
for _ in $(seq 1 600); do
  [ "$(wc -l <"$tmp/killed/frames.jsonl" 2>/dev/null || echo 0)" -ge 5 ] && break
  sleep 0.1
done
kill -9 $pid
wait $pid 2>/dev/null
lines=$(wc -l <"$tmp/killed/frames.jsonl")
[ "$lines" -ge 5 ] && ok || bad "killed recording has only $lines lines"
# every complete line's image exists and decodes: track reads them all
"$mr" track --input "$tmp/killed" --print-detections >"$tmp/killed.out" 2>"$tmp/killed.err" && ok || bad "killed recording unreadable: $(cat "$tmp/killed.err")"
[ "$(wc -l <"$tmp/killed.out")" -ge "$lines" ] && ok || bad "killed recording: $(wc -l <"$tmp/killed.out") of $lines frames readable"
# an image being written when the process died stays a temporary file that
# no line refers to; every line's image is complete
grep -q '\.tmp\.' "$tmp/killed/frames.jsonl" && bad "a frame line refers to a temporary file" || ok

# --- calibrate (CPU-rendered board images) --------------------------------
"$mr" synth --calibration "$tmp/calib" >/dev/null 2>"$tmp/calib.err" && ok || bad "synth --calibration: $(cat "$tmp/calib.err")"
if "$mr" calibrate --images "$tmp/calib/images" --board "$tmp/calib/board.json" --out "$tmp/calib/cam.json" >"$tmp/cal.out" 2>"$tmp/cal.err"; then
  ok
  fx=$(grep -o '"fx":[^,]*' "$tmp/calib/cam.json" | tr -dc '0-9.')
  awk -v f="$fx" 'BEGIN { exit !(f > 495 && f < 505) }' && ok || bad "calibrated fx $fx, expected 500 +- 1%"
  grep -q "RMS reprojection error" "$tmp/cal.out" && ok || bad "calibrate did not report the RMS"
else
  bad "calibrate failed: $(cat "$tmp/cal.err")"
fi
expect_fail calib_missing_board "$tmp/cam2.json" -- "$mr" calibrate --images "$tmp/calib/images" --board "$tmp/nope.json" --out "$tmp/cam2.json"
mkdir -p "$tmp/few" && cp "$tmp/calib/images/board_00.png" "$tmp/few/"
expect_fail calib_too_few "$tmp/cam3.json" -- "$mr" calibrate --images "$tmp/few" --board "$tmp/calib/board.json" --out "$tmp/cam3.json"

# --- bench tracking (a few frames, quick settings: it only has to run) ---
"$mr" bench tracking --recording "$rec" --frames 6 --quick --out "$tmp/bench" >"$tmp/bench.out" 2>"$tmp/bench.err" \
  && [ -s "$tmp/bench/bench_tracking.csv" ] && [ -s "$tmp/bench/bench_tracking.svg" ] && grep -q "opencv-aruco" "$tmp/bench/bench_tracking.csv" \
  && ok || bad "bench tracking: $(cat "$tmp/bench.err")"

# --- replay and synth need a GL device---------------------------------------
"$mr" demo --out "$tmp/demo" >"$tmp/demo.log" 2>&1
if need_device $? "$tmp/demo.log" "replay and synth (mrcheck demo)"; then
  for f in recording/frames.jsonl recording/groundtruth.jsonl calib/board.json; do
    [ -s "$tmp/demo/$f" ] && ok || bad "demo did not write $f"
  done
  scene=$tmp/demo/scene_planned.json
  "$mr" replay "$rec" --scene "$scene" --out "$tmp/rp1" --from 20 --to 100 --every 40 >/dev/null 2>"$tmp/rp1.err" && ok || bad "replay: $(cat "$tmp/rp1.err")"
  "$mr" replay "$rec" --scene "$scene" --out "$tmp/rp2" --from 20 --to 100 --every 40 >/dev/null 2>&1 && ok || bad "replay 2"
  n=0
  for f in "$tmp"/rp1/overlay_*.png; do
    cmp -s "$f" "$tmp/rp2/$(basename "$f")" && n=$((n + 1)) || bad "replay differs: $(basename "$f")"
  done
  [ $n -eq 3 ] && ok || bad "replay wrote $n images, expected 3 (frames 20, 60, 100)"
  cmp -s "$tmp/rp1/replay.jsonl" "$tmp/rp2/replay.jsonl" && ok || bad "replay.jsonl differs"
  "$mr" replay "$rec" --scene "$scene" --out "$tmp/rp5" --from 40 --to 50 --video "$tmp/rp5.avi" >/dev/null 2>"$tmp/rp5.err" \
    && [ "$("$mr" track --input "$tmp/rp5.avi" --print-detections 2>/dev/null | wc -l)" -eq 11 ] && ok || bad "replay --video: $(cat "$tmp/rp5.err")"
  expect_fail replay_not_recording "" -- "$mr" replay "$tmp" --scene "$scene" --out "$tmp/rp3"
  expect_fail replay_bad_range "" -- "$mr" replay "$rec" --scene "$scene" --out "$tmp/rp4" --from 50 --to 10
  "$mr" synth --out "$tmp/syn" --frames 3 --motion-blur 1 >/dev/null 2>"$tmp/syn.err" && [ "$(wc -l <"$tmp/syn/groundtruth.jsonl")" -eq 3 ] \
    && ok || bad "synth: $(cat "$tmp/syn.err")"
fi
ls "$tmp"/*.tmp.* >/dev/null 2>&1 && bad "temporary files left behind" || ok

cli_finish cli_track
