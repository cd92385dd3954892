#!/usr/bin/env bash
# Batch commands stop cleanly and leave no debris: `replay` on the shipped
# recording, sent SIGINT (and SIGTERM) at a random moment after its first
# overlay, leaves a folder whose replay.jsonl lists exactly the images
# present (each one whole) and says so in one line; a second run into it is
# refused without --force and accepted with it; a run that fails before
# writing (a range past the recording's end) leaves no folder; `track`
# stopped by SIGINT still writes its poses file and a summary.
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

cli_finish cli_batch_stop
