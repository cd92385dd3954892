#!/usr/bin/env bash
# `mrcheck study` with the rating and the task design, end to end: plans
# from condition folders (virtual/video, conflict/no-conflict with
# answers.json), the run window under Xvfb driven by --script (ratings 1..7
# and X per scale; a choice; a tap on the image and Confirm), each run
# killed with kill -9 after a few answers and resumed at the next trial,
# and analyze's files. Bad input gives one line and no output.
# Usage: cli_study_designs.sh MRCHECK TMPDIR. Exit 77 = skipped (no Xvfb / no GL).
set -u
mr=$1
tmp=$2
if [ -z "${DISPLAY:-}" ]; then
  if ! command -v xvfb-run >/dev/null 2>&1; then
    echo "cli_study_designs: SKIPPED: no display and Xvfb is not installed (apt-get install xvfb xauth)"
    exit 77
  fi
  exec xvfb-run -a -s "-screen 0 1024x768x24" bash "$0" "$@"
fi
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"
jget() { sed -n "s/^\t\"$2\":\t\(.*\),\{0,1\}$/\1/p" "$1" | sed 's/,$//; s/^"//; s/"$//' | head -1; }

# Images to lay out: two views of the demo hall under three AO methods.
"$mr" study stimuli --family ao --out "$tmp/ao" --views 2 --width 96 --height 72 --gt-rays 4 >"$tmp/st.log" 2>&1
if ! need_device $? "$tmp/st.log" "study stimuli"; then cli_finish cli_study_designs; fi

# kill_after VOTES PID N: waits for N lines in VOTES, then kill -9.
kill_after() {
  for _ in $(seq 1 300); do
    [ -f "$1" ] && [ "$(wc -l <"$1")" -ge "$3" ] && break
    kill -0 "$2" 2>/dev/null || break
    sleep 0.1
  done
  kill -9 "$2" 2>/dev/null
  wait "$2" 2>/dev/null
}

# --- rating: Scheer & Keutel's D1, D2, D3, virtual and over the camera image
"$mr" study stimuli --family depth --out "$tmp/r" --views 2 --width 96 --height 72 >"$tmp/sd.log" 2>&1 && ok || bad "depth stimuli: $(cat "$tmp/sd.log")"
[ "$(ls "$tmp/r" | tr '\n' ' ')" = "video virtual " ] && [ "$(ls "$tmp/r/video" | tr '\n' ' ')" = "D1 D2 D3 " ] && ok || bad "depth stimuli: $(ls -R "$tmp/r")"
cmp -s "$tmp/r/virtual/D1/hall_v0.png" "$tmp/r/virtual/D2/hall_v0.png" && bad "depth: D1 and D2 give the same image" || ok
cmp -s "$tmp/r/virtual/D2/hall_v0.png" "$tmp/r/virtual/D3/hall_v0.png" && bad "depth: D2 and D3 give the same image" || ok
cmp -s "$tmp/r/virtual/D2/hall_v0.png" "$tmp/r/video/D2/hall_v0.png" && bad "depth: the video condition shows no camera image" || ok
"$mr" study plan "$tmp/r" --design rating --scales occlusion,contrast --out "$tmp/rplan.json" --fixation-ms 50 >"$tmp/rp.log" 2>&1 && ok || bad "rating plan: $(cat "$tmp/rp.log")"
grep -q "(rating): 12 trials per participant, 1 schedule (3 methods, 2 stimuli, blocks virtual video)" "$tmp/rp.log" && ok ||
  bad "rating plan: expected 2 conditions x 3 methods x 2 stimuli: $(cat "$tmp/rp.log")"
rv="$tmp/rvotes.jsonl"
printf '0 tap @r5\n0 tap @rx\n0 tap @r2\n0 tap @r7\n0 tap @r1\n0 tap @r1\n60 quit\n' >"$tmp/rs1.txt"
"$mr" study run "$tmp/rplan.json" --participant a1 --out "$rv" --script "$tmp/rs1.txt" --size 900x700 >"$tmp/rr1.log" 2>&1 &
kill_after "$rv" $! 3
rc=$?
if [ "$(wc -l <"$rv" 2>/dev/null || echo 0)" -ne 3 ]; then
  if [ $rc -eq $MR_EXIT_NODEVICE ]; then skip_part "study run (no display/GL)"; cli_finish cli_study_designs; fi
  bad "rating run 1: expected 3 answers before the kill: $(cat "$rv" 2>/dev/null) $(cat "$tmp/rr1.log")"
else
  ok
fi
sed -n 1p "$rv" | grep -q '"design":"rating",.*"ratings":\[5,"X"\]' && ok || bad "rating run 1, first answer: $(sed -n 1p "$rv")"
sed -n 3p "$rv" | grep -q '"ratings":\[1,1\]' && ok || bad "rating run 1, third answer: $(sed -n 3p "$rv")"
{
  for _ in 1 2 3; do echo "0 tap @r6"; echo "0 tap @r4"; done
  echo "0 tap @continue" # the break before the video condition
  for _ in 1 2 3 4 5 6; do echo "0 tap @r6"; echo "0 tap @r4"; done
  echo "0 state $tmp/rst.json"
  echo "0 quit"
} >"$tmp/rs2.txt"
timeout 120 "$mr" study run "$tmp/rplan.json" --participant a1 --out "$rv" --script "$tmp/rs2.txt" --size 900x700 >"$tmp/rr2.log" 2>&1 && ok || bad "rating run 2: $(cat "$tmp/rr2.log")"
grep -q "resuming at trial 4 of 12 (3 answered)" "$tmp/rr2.log" && ok || bad "rating run 2 did not resume at trial 4: $(cat "$tmp/rr2.log")"
[ "$(jget "$tmp/rst.json" done)" = "true" ] && ok || bad "rating run 2 did not finish: $(cat "$tmp/rst.json" 2>/dev/null)"
[ "$(grep -c '"design":"rating"' "$rv")" -eq 12 ] && [ "$(grep -o '"trial":[0-9]*' "$rv" | sort -u | wc -l)" -eq 12 ] && ok ||
  bad "rating: expected 12 answers of 12 trials: $(cat "$rv")"
"$mr" study analyze "$rv" --plan "$tmp/rplan.json" --out "$tmp/ra" >"$tmp/ra.log" 2>&1 && ok || bad "rating analyze: $(cat "$tmp/ra.log")"
for f in means.csv anova.csv posthoc.csv ttest.csv chart_virtual.svg chart_video.svg summary.md; do
  [ -s "$tmp/ra/$f" ] && ok || bad "rating analyze: no $f"
done
grep -q "too few participants" "$tmp/ra/summary.md" && ok || bad "rating analyze of one participant should say too few: $(head -30 "$tmp/ra/summary.md")"
# Scheer & Keutel's overall question first in each condition: all three side by side.
"$mr" study plan "$tmp/r" --design rating --scales occlusion --overall --out "$tmp/roplan.json" --fixation-ms 50 >"$tmp/rop.log" 2>&1 &&
  grep -q "(rating): 16 trials per participant" "$tmp/rop.log" && ok || bad "rating plan --overall: $(cat "$tmp/rop.log")"
printf '0 tap @p2\n0 state %s\n0 tap @p3\n0 tap @r4\n0 quit\n' "$tmp/ost.json" >"$tmp/ro.txt"
timeout 60 "$mr" study run "$tmp/roplan.json" --participant o1 --out "$tmp/ovotes.jsonl" --script "$tmp/ro.txt" --size 900x500 >"$tmp/ro.log" 2>&1 && ok || bad "overall run: $(cat "$tmp/ro.log")"
[ "$(jget "$tmp/ost.json" images)" = "3" ] && ok || bad "overall: three images side by side: $(cat "$tmp/ost.json" 2>/dev/null)"
[ "$(grep -c '"left":"\*",.*"choice":[0-2]' "$tmp/ovotes.jsonl")" -eq 2 ] && [ "$(grep -c '"ratings":\[4\]' "$tmp/ovotes.jsonl")" -eq 1 ] && ok ||
  bad "overall votes: $(cat "$tmp/ovotes.jsonl")"
"$mr" study analyze "$tmp/ovotes.jsonl" --plan "$tmp/roplan.json" --out "$tmp/roa" >"$tmp/roa.log" 2>&1 && [ -s "$tmp/roa/overall.csv" ] && ok ||
  bad "overall analyze: $(cat "$tmp/roa.log")"
expect_fail an_rating_noplan "$tmp/ra2" -- "$mr" study analyze "$rv" --out "$tmp/ra2"
expect_fail plan_rating_nocond "$tmp/px.json" -- "$mr" study plan "$tmp/ao" --design rating --out "$tmp/px.json"
expect_fail plan_rating_scale "$tmp/px.json" -- "$mr" study plan "$tmp/r" --design rating --scales "a b" --out "$tmp/px.json"

# --- task: conflict asks which hidden object is nearer, no-conflict where the pipe crosses the wall
for c in conflict no-conflict; do
  for m in adaptive alpha g0; do
    mkdir -p "$tmp/t/$c/$m"
    for s in 0 1; do for q in 0 1; do cp "$tmp/ao/hbao/hall_v$s.png" "$tmp/t/$c/$m/scene$s.t$q.png"; done; done
  done
done
printf '{"scene0.t0": {"question": "nearer", "labels": ["A", "B"], "correct": "A"},
 "scene0.t1": {"question": "nearer", "labels": ["A", "B"], "correct": "B"},
 "scene1.t0": {"question": "nearer", "labels": ["A", "B"], "correct": "A"},
 "scene1.t1": {"question": "nearer", "labels": ["A", "B"], "correct": "A"}}\n' >"$tmp/t/conflict/answers.json"
printf '{"scene0.t0": {"question": "crossing", "x": 20, "y": 40, "units_per_px": 0.05},
 "scene0.t1": {"question": "crossing", "x": 20, "y": 40, "units_per_px": 0.05},
 "scene1.t0": {"question": "crossing", "x": 20, "y": 40, "units_per_px": 0.05},
 "scene1.t1": {"question": "crossing", "x": 20, "y": 40, "units_per_px": 0.05}}\n' >"$tmp/t/no-conflict/answers.json"
"$mr" study plan "$tmp/t" --design task --participants 3 --out "$tmp/tplan.json" --fixation-ms 50 >"$tmp/tp.log" 2>&1 && ok || bad "task plan: $(cat "$tmp/tp.log")"
grep -q "(task): 8 trials per participant, 3 schedules" "$tmp/tp.log" && ok || bad "task plan: $(cat "$tmp/tp.log")"
tv="$tmp/tvotes.jsonl"
printf '0 tap @a\n0 tap @b\n60 quit\n' >"$tmp/ts1.txt"
"$mr" study run "$tmp/tplan.json" --participant P02 --out "$tv" --script "$tmp/ts1.txt" --size 900x700 >"$tmp/tr1.log" 2>&1 &
kill_after "$tv" $! 2
[ "$(wc -l <"$tv" 2>/dev/null || echo 0)" -eq 2 ] && ok || bad "task run 1: expected 2 answers before the kill: $(cat "$tv" 2>/dev/null) $(cat "$tmp/tr1.log")"
sed -n 2p "$tv" | grep -q '"design":"task",.*"choice":1' && ok || bad "task run 1, second answer: $(sed -n 2p "$tv")"
{
  echo "0 tap @a"; echo "0 tap @a"; echo "0 tap @continue"
  for _ in 1 2 3 4; do echo "0 tap @image 0.3 0.6"; echo "0 tap @confirm"; done
  echo "0 state $tmp/tst.json"
  echo "0 quit"
} >"$tmp/ts2.txt"
timeout 120 "$mr" study run "$tmp/tplan.json" --participant P02 --out "$tv" --script "$tmp/ts2.txt" --size 900x700 >"$tmp/tr2.log" 2>&1 && ok || bad "task run 2: $(cat "$tmp/tr2.log")"
grep -q "resuming at trial 3 of 8 (2 answered)" "$tmp/tr2.log" && ok || bad "task run 2 did not resume at trial 3: $(cat "$tmp/tr2.log")"
[ "$(jget "$tmp/tst.json" done)" = "true" ] && ok || bad "task run 2 did not finish: $(cat "$tmp/tst.json" 2>/dev/null)"
[ "$(grep -c '"tap":\[' "$tv")" -eq 4 ] && [ "$(grep -c '"choice":' "$tv")" -eq 4 ] && ok || bad "task: 4 choices and 4 taps expected: $(cat "$tv")"
expect_fail run_task_who "" -- "$mr" study run "$tmp/tplan.json" --participant P09 --out "$tmp/tvx.jsonl"
"$mr" study analyze "$tv" --plan "$tmp/tplan.json" --out "$tmp/ta" >"$tmp/ta.log" 2>&1 && ok || bad "task analyze: $(cat "$tmp/ta.log")"
for f in trials.csv scores.csv tests.csv posthoc.csv chart_conflict.svg chart_no-conflict.svg summary.md; do
  [ -s "$tmp/ta/$f" ] && ok || bad "task analyze: no $f"
done
# The tap at 30 %, 60 % of the 96 x 72 image: (28.8, 43.2), 9.364 px from (20, 40), 0.468 units.
[ "$(grep -c ',crossing,"28.8 43.2",1,9.364,0.468188,' "$tmp/ta/trials.csv")" -eq 4 ] && ok || bad "task taps scored: $(grep crossing "$tmp/ta/trials.csv")"
# The xray family: Kalkofen's scenes with their answers, planned as a task study.
"$mr" study stimuli --family xray --out "$tmp/x" --views 2 --targets 2 --width 96 --height 72 >"$tmp/sx.log" 2>&1 && ok || bad "xray stimuli: $(cat "$tmp/sx.log")"
grep -q "24 images of family xray" "$tmp/sx.log" && ok || bad "xray: expected 2 conditions x 2 scenes x 2 targets x 3 modes: $(cat "$tmp/sx.log")"
cmp -s "$tmp/x/conflict/adaptive/scene0.t0.png" "$tmp/x/no-conflict/adaptive/scene0.t0.png" && bad "xray: conflict and no-conflict look the same" || ok
cmp -s "$tmp/x/conflict/alpha/scene0.t0.png" "$tmp/x/conflict/adaptive/scene0.t0.png" && bad "xray: alpha and adaptive look the same" || ok
grep -q '"question":	"crossing"' "$tmp/x/conflict/answers.json" && grep -q '"correct":	"\(tall\|wide\)"' "$tmp/x/conflict/answers.json" && ok ||
  bad "xray answers: $(cat "$tmp/x/conflict/answers.json")"
"$mr" study plan "$tmp/x" --design task --participants 6 --out "$tmp/xplan.json" >"$tmp/xp.log" 2>&1 && grep -q "(task): 8 trials per participant, 6 schedules" "$tmp/xp.log" && ok ||
  bad "xray plan: $(cat "$tmp/xp.log")"
expect_fail plan_task_nokeys "$tmp/px.json" -- "$mr" study plan "$tmp/r" --design task --out "$tmp/px.json"
cli_finish cli_study_designs
