#!/usr/bin/env bash
# Worked example of Kalkofen et al.'s task design (docs/study/README.md):
# three scenes with six targets each behind a wall (which hidden box is
# nearer; tap where the hidden pipe meets the wall) through alpha, g0 and
# adaptive ghosting, with conflicting colours (Experiment 1) and without
# (Experiment 2); a plan rotating the modes over the scenes per
# participant; 18 simulated participants with known effects; the
# analysis (RM-ANOVA where the residuals pass, else Friedman + Wilcoxon).
# Usage: bash docs/study/task.sh [BUILD_DIR] [OUT_DIR]
set -euo pipefail
mr=${1:-build}/mrcheck
out=${2:-study-task}
rm -rf "$out" && mkdir -p "$out"
"$mr" study stimuli --family xray --out "$out/stimuli" --views 3 --targets 6
"$mr" study plan "$out/stimuli" --design task --participants 18 --seed 1 --out "$out/plan.json"
# P(right) and tap error sigma (px) per condition and mode: with conflicting
# colours adaptive ghosting keeps the occluder's structure and the hidden
# parts apart; without the conflict g0 and adaptive do equally well.
SIM='{"conflict": {"adaptive": [0.92, 6], "alpha": [0.55, 25], "g0": [0.6, 22]},
      "no-conflict": {"adaptive": [0.9, 6], "alpha": [0.65, 18], "g0": [0.9, 7]}}' \
python3 - "$out/plan.json" "$out/stimuli" "$out/votes.jsonl" <<'PY'
import json, math, os, random, sys
plan = json.load(open(sys.argv[1]))
sim = json.loads(os.environ["SIM"])
keys = {c: json.load(open(os.path.join(sys.argv[2], c, "answers.json"))) for c in ("conflict", "no-conflict")}
cond = {"I": "conflict", "II": "no-conflict"}
random.seed(9)
with open(sys.argv[3], "w") as f:
    for who in plan["participants"]:
        for t in who["trials"]:
            c, m = cond[t["block"]], t["left"]
            k = keys[c][t["stimulus"]]
            v = {"plan": plan["id"], "participant": who["id"], "design": "task", "block": t["block"],
                 "trial": t["trial"], "stimulus": t["stimulus"], "left": m, "right": m, "ms": 0, "time_unix": 0}
            if k["question"] == "nearer":
                right = random.random() < sim[c][m][0]
                ok = k["labels"].index(k["correct"])
                v["choice"] = ok if right else 1 - ok
            else:
                e, a = abs(random.gauss(0, sim[c][m][1])), random.uniform(0, 2 * math.pi)
                v["tap"] = [k["x"] + e * math.cos(a), k["y"] + e * math.sin(a)]
            f.write(json.dumps(v, separators=(",", ":")) + "\n")
PY
"$mr" study analyze "$out/votes.jsonl" --plan "$out/plan.json" --out "$out/analysis" --adjust holm
