#!/usr/bin/env bash
# `mrcheck study` end to end: stimuli of the demo hall (ao with its
# ray-traced reference, ghost without one, shadows of the hall and a
# suite case with the ground truth as the reference), plans reproducible
# from the seed, the run window under Xvfb driven by --script (three buttons and the
# slider), a run killed with kill -9 that resumes at the next unanswered
# trial (also after a torn last line), answers twice, votes for another
# plan, and analyze's files. Bad input gives one line and no output.
# Usage: cli_study.sh MRCHECK TMPDIR. Exit 77 = skipped (no Xvfb / no GL).
set -u
mr=$1
tmp=$2
if [ -z "${DISPLAY:-}" ]; then
  if ! command -v xvfb-run >/dev/null 2>&1; then
    echo "cli_study: SKIPPED: no display and Xvfb is not installed (apt-get install xvfb xauth)"
    exit 77
  fi
  exec xvfb-run -a -s "-screen 0 1024x768x24" bash "$0" "$@"
fi
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"
jget() { sed -n "s/^\t\"$2\":\t\(.*\),\{0,1\}$/\1/p" "$1" | sed 's/,$//; s/^"//; s/"$//' | head -1; }

# --- stimuli
"$mr" study stimuli --family ao --out "$tmp/ao" --views 2 --width 96 --height 72 --gt-rays 16 >"$tmp/st.log" 2>&1
if ! need_device $? "$tmp/st.log" "study stimuli"; then cli_finish cli_study; fi
n=$(ls "$tmp"/ao/*/hall_v*.png | wc -l)
[ "$n" -eq 12 ] && ok || bad "ao stimuli: $n images, expected 2 views x (5 methods + reference)"
[ -f "$tmp/ao/reference/hall_v1.png" ] && ok || bad "ao: no reference image"
"$mr" study stimuli --family ghost --out "$tmp/ghost" --views 1 --width 96 --height 72 >"$tmp/sg.log" 2>&1 && ok || bad "ghost stimuli: $(cat "$tmp/sg.log")"
[ "$(ls "$tmp"/ghost | tr '\n' ' ')" = "adaptive alpha g0 " ] && ok || bad "ghost methods: $(ls "$tmp/ghost")"
cmp -s "$tmp/ghost/alpha/hall_v0.png" "$tmp/ghost/adaptive/hall_v0.png" && bad "ghost: alpha and adaptive give the same image" || ok
# shadows: Hecher's set, two categories here (two scenes each), the
# thesis's three methods and the ground truth as the reference; hard
# shadows only when asked; block II needs the reference.
"$mr" study stimuli --family shadows --out "$tmp/sh" --cases 2 --width 96 --height 54 --gt-samples 16 >"$tmp/ss.log" 2>&1 && ok || bad "shadows stimuli: $(cat "$tmp/ss.log")"
[ "$(ls "$tmp"/sh | grep -v "\.csv$" | tr '\n' ' ')" = "bp pcf pcss reference " ] && ok || bad "shadows methods: $(ls "$tmp/sh")"
for m in bp pcf pcss reference; do
  [ "$(ls "$tmp/sh/$m" 2>/dev/null | tr '\n' ' ')" = "simple_constant.a.png simple_constant.b.png simple_constant_overlap.a.png simple_constant_overlap.b.png " ] && ok ||
    bad "shadows $m: $(ls "$tmp/sh/$m" 2>&1)"
done
grep -q "16 images of family shadows" "$tmp/ss.log" && ok || bad "shadows: expected 4 stimuli x 4 images: $(cat "$tmp/ss.log")"
# The thesis's check of the scene pairs: each method's difference to the reference.
[ "$(grep -c '^simple_constant[a-z_]*,simple_constant[a-z_]*\.[ab],\(bp\|pcf\|pcss\),0\.[0-9]*,0\.[0-9]*,0\.[0-9]*$' "$tmp/sh/differences.csv")" -eq 12 ] && ok ||
  bad "shadows: differences.csv: $(cat "$tmp/sh/differences.csv")"
# The PNG header's width and height (big-endian at bytes 16..23).
[ "$(od -An -tu1 -j16 -N8 "$tmp/sh/pcf/simple_constant.a.png" | tr -s ' ')" = " 0 0 0 96 0 0 0 54" ] && ok ||
  bad "shadows: not 96 x 54: $(od -An -tu1 -j16 -N8 "$tmp/sh/pcf/simple_constant.a.png")"
cmp -s "$tmp/sh/pcf/simple_constant.a.png" "$tmp/sh/pcf/simple_constant.b.png" && bad "shadows: scenes a and b are the same image" || ok
cmp -s "$tmp/sh/pcf/simple_constant.a.png" "$tmp/sh/reference/simple_constant.a.png" && bad "shadows: the reference is pcf" || ok
"$mr" study stimuli --family shadows --out "$tmp/shh" --cases 1 --width 48 --height 27 --gt-samples 4 --hard >"$tmp/ssh.log" 2>&1 && ok || bad "shadows --hard: $(cat "$tmp/ssh.log")"
[ "$(ls "$tmp"/shh | grep -v "\.csv$" | tr '\n' ' ')" = "bp hard pcf pcss reference " ] && ok || bad "shadows --hard methods: $(ls "$tmp/shh")"
# The default blocks I,II,III: block II shows the reference, so it needs one.
"$mr" study plan "$tmp/sh" --out "$tmp/plan_sh.json" --seed 2 --fixation-ms 50 --participants 4 >"$tmp/psh.log" 2>&1 && ok || bad "plan of shadows: $(cat "$tmp/psh.log")"
# 4 methods: C(4,2) = 6 pairs + 1 identical per category, 2 categories, 3 blocks.
grep -q "42 trials per participant, 4 schedules (4 methods with the reference, 4 stimuli, blocks I II III)" "$tmp/psh.log" && ok ||
  bad "plan of shadows: expected blocks I,II,III with 42 trials: $(cat "$tmp/psh.log")"
expect_fail stim_cases "" -- "$mr" study stimuli --family shadows --out "$tmp/sx" --cases 14

# --- plan: any DIR/<method>/<stimulus>.png folder; three methods, two stimuli
mkdir -p "$tmp/small"
cp -r "$tmp/ao/alchemy" "$tmp/ao/hbao" "$tmp/ao/reference" "$tmp/small/"
"$mr" study plan "$tmp/small" --out "$tmp/plan.json" --seed 5 --blocks I,II --fixation-ms 50 >"$tmp/p.log" 2>&1 && ok || bad "plan: $(cat "$tmp/p.log")"
grep -q "16 trials" "$tmp/p.log" && ok || bad "plan: expected 2 blocks x 2 stimuli x (3 pairs + 1 identical): $(cat "$tmp/p.log")"
"$mr" study plan "$tmp/small" --out "$tmp/plan_b.json" --seed 5 --blocks I,II --fixation-ms 50 >/dev/null 2>&1
cmp -s "$tmp/plan.json" "$tmp/plan_b.json" && ok || bad "plan: the same seed gave another plan"
"$mr" study plan "$tmp/small" --out "$tmp/plan2.json" --seed 6 --blocks I,II --fixation-ms 50 >/dev/null 2>&1
cmp -s "$tmp/plan.json" "$tmp/plan2.json" && bad "plan: another seed gave the same plan" || ok
expect_fail plan_noout "" -- "$mr" study plan "$tmp/small"
expect_fail plan_nodir "$tmp/px.json" -- "$mr" study plan "$tmp/nonexistent" --out "$tmp/px.json"
expect_fail plan_blocks "$tmp/px.json" -- "$mr" study plan "$tmp/small" --out "$tmp/px.json" --blocks I,IV
expect_fail plan_seed "$tmp/px.json" -- "$mr" study plan "$tmp/small" --out "$tmp/px.json" --seed -3
expect_fail plan_fix "$tmp/px.json" -- "$mr" study plan "$tmp/small" --out "$tmp/px.json" --fixation-ms 99999
expect_fail plan_noref "$tmp/px.json" -- "$mr" study plan "$tmp/ghost" --out "$tmp/px.json" --blocks I,II
expect_fail stim_family "" -- "$mr" study stimuli --family shadowz --out "$tmp/sx"
expect_fail study_sub "" -- "$mr" study nosuch

# --- run: three answers, then kill -9 while it waits
v="$tmp/votes.jsonl"
printf '0 tap @left\n0 tap @right\n0 tap @neutral\n60 quit\n' >"$tmp/run1.txt"
"$mr" study run "$tmp/plan.json" --participant p1 --out "$v" --script "$tmp/run1.txt" --size 800x600 >"$tmp/r1.log" 2>&1 &
pid=$!
for _ in $(seq 1 300); do
  [ -f "$v" ] && [ "$(wc -l <"$v")" -ge 3 ] && break
  kill -0 $pid 2>/dev/null || break
  sleep 0.1
done
kill -9 $pid 2>/dev/null
wait $pid 2>/dev/null
rc1=$?
if [ "$(wc -l <"$v" 2>/dev/null || echo 0)" -ne 3 ]; then
  if [ $rc1 -eq $MR_EXIT_NODEVICE ]; then skip_part "study run (no display/GL: $(head -c 300 "$tmp/r1.log"))"; cli_finish cli_study; fi
  bad "run 1: expected 3 votes before the kill: $(cat "$v" 2>/dev/null) $(cat "$tmp/r1.log")"
else
  ok
fi
grep -q '"trial":2,.*"answer":"neutral"' "$v" && ok || bad "run 1: third vote: $(sed -n 3p "$v")"
# A torn line, as a kill in the middle of a write would leave.
printf '{"plan":"' >>"$v"
# The second run resumes at trial 4: five answers finish block I, the break
# before block II and Continue, the state is taken on the first pair of
# block II (the reference shown), eight more.
{
  for _ in 1 2 3 4 5; do echo "0 tap @left"; done
  echo "0 state $tmp/st_break.json"
  echo "0 tap @continue"
  echo "0 state $tmp/st_b2.json"
  echo "0 shot $tmp/shot_b2.png"
  for _ in 1 2 3 4 5 6 7 8; do echo "0 tap @right"; done
  echo "0 state $tmp/st_end.json"
  echo "0 quit"
} >"$tmp/run2.txt"
timeout 120 "$mr" study run "$tmp/plan.json" --participant p1 --out "$v" --script "$tmp/run2.txt" --size 800x600 >"$tmp/r2.log" 2>&1 && ok || bad "run 2 failed: $(cat "$tmp/r2.log")"
grep -q "resuming at trial 4 of 16 (3 answered)" "$tmp/r2.log" && ok || bad "run 2 did not resume at trial 4: $(cat "$tmp/r2.log")"
grep -q "torn" "$tmp/r2.log" && ok || bad "run 2 said nothing about the torn line: $(cat "$tmp/r2.log")"
[ "$(jget "$tmp/st_break.json" break)" = "true" ] && [ "$(jget "$tmp/st_break.json" images)" = "0" ] && ok ||
  bad "between blocks I and II a break screen: $(cat "$tmp/st_break.json" 2>/dev/null)"
[ "$(jget "$tmp/st_b2.json" block)" = "II" ] && [ "$(jget "$tmp/st_b2.json" images)" = "3" ] && ok ||
  bad "block II should show the reference above the pair: $(cat "$tmp/st_b2.json" 2>/dev/null)"
[ "$(jget "$tmp/st_end.json" done)" = "true" ] && ok || bad "run 2 did not finish: $(cat "$tmp/st_end.json" 2>/dev/null)"
good=$(grep -c '^{"plan":"[0-9a-f]\{16\}",' "$v")
trials=$(grep -o '"trial":[0-9]*' "$v" | sort -u | wc -l)
[ "$good" -eq 16 ] && [ "$trials" -eq 16 ] && ok || bad "votes: $good lines, $trials distinct trials (expected 16 each)"
grep -q '^{"plan":"$' "$v" && ok || bad "the torn line was not kept as it was"
sed -n 5p "$v" | grep -q '"trial":3,' && ok || bad "run 2's first vote (after the sealed torn line) is not trial 3: $(sed -n 4,5p "$v")"
"$mr" study run "$tmp/plan.json" --participant p1 --out "$v" >"$tmp/r3.log" 2>&1 && grep -q "answered all 16" "$tmp/r3.log" && ok ||
  bad "a finished participant: $(cat "$tmp/r3.log")"
head -3 "$v" >"$tmp/votes_p1.jsonl"
expect_fail run_otherplan "" -- "$mr" study run "$tmp/plan2.json" --participant p1 --out "$tmp/votes_p1.jsonl"
expect_fail run_noplan "" -- "$mr" study run "$tmp/nonexistent.json" --participant p1 --out "$tmp/vx.jsonl"
expect_fail run_nopart "" -- "$mr" study run "$tmp/plan.json" --out "$tmp/vx.jsonl"
printf '0 fly @left\n' >"$tmp/badscript.txt"
expect_fail run_script "" -- "$mr" study run "$tmp/plan.json" --participant p9 --out "$tmp/vx.jsonl" --script "$tmp/badscript.txt"

# --- the slider: its centre snaps to no preference
printf '0 drag @slider 0.5 0.1\n0 tap @vote\n0 drag @slider 0.5 0.52\n0 tap @vote\n0 quit\n' >"$tmp/slider.txt"
timeout 60 "$mr" study run "$tmp/plan.json" --participant p2 --out "$tmp/votes2.jsonl" --slider --script "$tmp/slider.txt" --size 800x600 >"$tmp/rs.log" 2>&1 && ok || bad "slider run: $(cat "$tmp/rs.log")"
sed -n 1p "$tmp/votes2.jsonl" | grep -q '"answer":"left","slider":-0\.[0-9]*' && ok || bad "slider left: $(sed -n 1p "$tmp/votes2.jsonl")"
sed -n 2p "$tmp/votes2.jsonl" | grep -q '"answer":"neutral","slider":0,' && ok || bad "slider snap: $(sed -n 2p "$tmp/votes2.jsonl")"

# --- answered twice: the first answer is kept, with a warning
sed -n 1p "$v" | sed 's/"answer":"left"/"answer":"right"/' >>"$v"

# --- analyze
"$mr" study analyze "$v" "$tmp/votes2.jsonl" --plan "$tmp/plan.json" --out "$tmp/an" >"$tmp/an.log" 2>&1 && ok || bad "analyze: $(cat "$tmp/an.log")"
grep -q "answered trial 0 of plan .* again" "$tmp/an.log" && ok || bad "analyze: no warning for the repeated answer: $(cat "$tmp/an.log")"
grep -q "18 votes" "$tmp/an.log" && ok || bad "analyze: expected 16 + 2 votes: $(cat "$tmp/an.log")"
for f in pairs.csv scores.csv consistence.csv participants.csv agreement.csv identical.csv summary.md chart_I.svg chart_II.svg; do
  [ -s "$tmp/an/$f" ] && ok || bad "analyze: no $f"
done
head -c 4 "$tmp/an/chart_II.svg" | grep -q "<svg" && ok || bad "chart_II.svg is not SVG"
grep -q "## Block II" "$tmp/an/summary.md" && ok || bad "summary without block II"
grep -q "^II,all,davidson,reference,0.000000,0.000000," "$tmp/an/scores.csv" && ok || bad "the reference is not fixed at 0: $(grep reference "$tmp/an/scores.csv" | head -3)"
! grep -qi "nan" "$tmp/an/scores.csv" && ok || bad "NaN in scores.csv"
# Votes of another plan only: a warning that names it, then one error.
"$mr" study analyze "$v" --plan "$tmp/plan2.json" --out "$tmp/an2" >"$tmp/an2.log" 2>&1
rc=$?
[ $rc -ne 0 ] && [ $rc -lt 128 ] && grep -q "not of this plan" "$tmp/an2.log" && grep -q "no votes to analyse" "$tmp/an2.log" && ok ||
  bad "analyze of another plan's votes (rc $rc): $(cat "$tmp/an2.log")"
[ ! -e "$tmp/an2/summary.md" ] && ok || bad "analyze of no votes wrote a summary"
expect_fail an_nofile "$tmp/an3" -- "$mr" study analyze "$tmp/nonexistent.jsonl" --out "$tmp/an3"
expect_fail an_noout "" -- "$mr" study analyze "$v"
expect_fail an_alpha "$tmp/an4" -- "$mr" study analyze "$v" --out "$tmp/an4" --alpha 2
cli_finish cli_study
