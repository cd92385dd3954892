#!/usr/bin/env bash
# Worked example of Hecher's pairwise design (docs/study/README.md): the
# thesis's stimulus set (13 categories x 2 scenes, pcf / pcss / bp against
# the ground truth; here at 320x180 to keep it quick, the default is the
# thesis's 800x450), a plan with a schedule per participant (own order,
# own scene per block, balanced groups A/B), 24 simulated participants who
# answer by Davidson's model with known strengths, and one who answers in
# circles (pcf > pcss > bp > reference > pcf: inconsistent, so the
# analysis excludes P25 and reports the results with and without).
# Usage: bash docs/study/pairwise.sh [BUILD_DIR] [OUT_DIR]
set -euo pipefail
mr=${1:-build}/mrcheck
out=${2:-study-pairwise}
rm -rf "$out" && mkdir -p "$out"
"$mr" study stimuli --family shadows --out "$out/stimuli" --width 320 --height 180 --gt-samples 64
"$mr" study plan "$out/stimuli" --participants 25 --seed 1 --out "$out/plan.json"
# Strengths (log scale, reference 0) per block question: "better" in block
# I and III-A, "plausible" in II and III-B; nu = 0.6. P25 answers in circles.
SIM='{"better": {"reference": 0.0, "bp": -0.1, "pcss": -0.3, "pcf": -0.6},
      "plausible": {"reference": 0.0, "bp": -0.2, "pcss": -0.6, "pcf": -1.4}}' \
python3 - "$out/plan.json" "$out/votes.jsonl" <<'PY'
import json, math, os, random, sys
plan = json.load(open(sys.argv[1]))
theta = json.loads(os.environ["SIM"])
nu = 0.6
random.seed(3)
with open(sys.argv[2], "w") as f:
    for who in plan["participants"]:
        for t in who["trials"]:
            q = "plausible" if t["block"] == "II" or (t["block"] == "III" and who["group"] == "B") else "better"
            a, b = t["left"], t["right"]
            if a == b:
                ans = "neutral" if random.random() < 0.75 else random.choice(["left", "right"])
            elif who["id"] == "P25":
                order = ["pcf", "pcss", "bp", "reference"]
                ia, ib = order.index(a), order.index(b)
                d = (ib - ia) % 4
                ans = "left" if d == 1 or (d == 2 and ia < ib) else "right"
            else:
                pa, pb = math.exp(theta[q][a]), math.exp(theta[q][b])
                pt = nu * math.sqrt(pa * pb)
                r = random.random() * (pa + pb + pt)
                ans = "left" if r < pa else "right" if r < pa + pb else "neutral"
            v = {"plan": plan["id"], "participant": who["id"], "block": t["block"], "trial": t["trial"],
                 "stimulus": t["stimulus"], "left": a, "right": b, "answer": ans,
                 "slider": {"left": -1, "right": 1, "neutral": 0}[ans], "ms": 0, "time_unix": 0}
            if "group" in who: v["group"] = who["group"]
            f.write(json.dumps(v, separators=(",", ":")) + "\n")
PY
"$mr" study analyze "$out/votes.jsonl" --plan "$out/plan.json" --out "$out/analysis"
