#!/usr/bin/env bash
# The README's worked example of `mrcheck study`: AO stimuli of the demo
# hall, a plan, one participant in the window (scripted, under Xvfb when
# there is no display), twelve simulated participants, and the analysis.
# The simulated participants answer by Davidson's model with the strengths
# in SIM_THETA (log scale, reference 0) and tie parameter nu = 0.5, so the
# analysis can be checked against the strengths it should recover.
# Usage: bash docs/study/example.sh [BUILD_DIR] [OUT_DIR]
set -euo pipefail
mr=${1:-build}/mrcheck
out=${2:-study-example}
rm -rf "$out" && mkdir -p "$out"
"$mr" study stimuli --family ao --out "$out/stimuli" --views 3
"$mr" study plan "$out/stimuli" --out "$out/plan.json" --seed 1 --fixation-ms 300
# One participant in the window: left, neutral, right in turn for 20 trials.
for i in $(seq 1 20); do
  case $((i % 3)) in 0) echo "0 tap @left" ;; 1) echo "0 tap @neutral" ;; *) echo "0 tap @right" ;; esac
  [ "$i" -eq 17 ] && echo "0 shot $out/window.png"
done >"$out/script.txt"
echo "0 quit" >>"$out/script.txt"
run=("$mr" study run "$out/plan.json" --participant window1 --out "$out/votes_window.jsonl" --script "$out/script.txt" --size 960x640)
if [ -n "${DISPLAY:-}" ]; then "${run[@]}"; else xvfb-run -a -s "-screen 0 1024x768x24" "${run[@]}"; fi
# Twelve simulated participants.
SIM_THETA='{"reference": 0.0, "alchemy": -0.4, "hbao": -0.8, "scheer": -1.2, "filion": -1.6, "crytek": -2.4}' \
python3 - "$out/plan.json" "$out/votes_sim.jsonl" <<'PY'
import json, math, os, random, sys
plan = json.load(open(sys.argv[1]))
theta = json.loads(os.environ["SIM_THETA"])
nu = 0.5
random.seed(7)
with open(sys.argv[2], "w") as f:
    for p in range(12):
        for t in plan["trials"]:
            a, b = t["left"], t["right"]
            if a == b:
                ans = "neutral" if random.random() < 0.8 else random.choice(["left", "right"])
            else:
                pa, pb = math.exp(theta[a]), math.exp(theta[b])
                pt = nu * math.sqrt(pa * pb)
                r = random.random() * (pa + pb + pt)
                ans = "left" if r < pa else "right" if r < pa + pb else "neutral"
            f.write(json.dumps({"plan": plan["id"], "participant": "sim%02d" % (p + 1), "block": t["block"],
                                "trial": t["trial"], "stimulus": t["stimulus"], "left": a, "right": b,
                                "answer": ans, "slider": {"left": -1, "right": 1, "neutral": 0}[ans],
                                "ms": 0, "time_unix": 0}, separators=(",", ":")) + "\n")
PY
"$mr" study analyze "$out/votes_window.jsonl" "$out/votes_sim.jsonl" --plan "$out/plan.json" --out "$out/analysis"
