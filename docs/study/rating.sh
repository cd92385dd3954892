#!/usr/bin/env bash
# Worked example of Scheer & Keutel's rating design (docs/study/README.md):
# D1 (no AO), D2 (their SSAO) and D3 (standard SSAO) of three hall views,
# virtual and over the camera image at alpha 0.5; a plan rating each image
# on the eight depth cues 1..7; one participant in the window (scripted,
# under Xvfb when there is no display); 22 simulated participants with
# known effects (SIM: mean rating per condition, method and cue; a random
# participant offset and noise on top), and the analysis (Tables 3 and 4).
# Usage: bash docs/study/rating.sh [BUILD_DIR] [OUT_DIR]
set -euo pipefail
mr=${1:-build}/mrcheck
out=${2:-study-rating}
rm -rf "$out" && mkdir -p "$out"
"$mr" study stimuli --family depth --out "$out/stimuli" --views 3
"$mr" study plan "$out/stimuli" --design rating --seed 1 --fixation-ms 300 --out "$out/plan.json"
# One participant in the window: 5 on every cue of the first 3 images.
for _ in $(seq 1 24); do echo "0 tap @r5"; done >"$out/script.txt"
echo "0 shot $out/window.png" >>"$out/script.txt"
echo "0 quit" >>"$out/script.txt"
run=("$mr" study run "$out/plan.json" --participant window1 --out "$out/votes_window.jsonl" --script "$out/script.txt" --size 960x720)
if [ -n "${DISPLAY:-}" ]; then "${run[@]}"; else xvfb-run -a -s "-screen 0 1024x768x24" "${run[@]}"; fi
# Occlusion and light & shadow profit from D2, most without the video;
# linear perspective from nothing (as the paper found).
SIM='{"virtual": {"D1": 3.0, "D2": 5.8, "D3": 4.6}, "video": {"D1": 4.0, "D2": 5.0, "D3": 4.8}}' \
python3 - "$out/plan.json" "$out/votes_sim.jsonl" <<'PY'
import json, os, random, sys
plan = json.load(open(sys.argv[1]))
base = json.loads(os.environ["SIM"])
cond = {"I": "virtual", "II": "video"}
random.seed(5)
with open(sys.argv[2], "w") as f:
    for p in range(22):
        off = random.gauss(0, 0.6)
        for t in plan["trials"]:
            m, c = t["left"], cond[t["block"]]
            r = []
            for s in plan["scales"]:
                mu = base[c][m] if s in ("occlusion", "light_and_shadow", "aerial_perspective") else 4.2
                r.append(max(1, min(7, round(mu + off + random.gauss(0, 0.8)))) if random.random() > 0.03 else "X")
            f.write(json.dumps({"plan": plan["id"], "participant": "sim%02d" % p, "design": "rating",
                                "block": t["block"], "trial": t["trial"], "stimulus": t["stimulus"], "left": m,
                                "right": m, "ratings": r, "ms": 0, "time_unix": 0}, separators=(",", ":")) + "\n")
PY
"$mr" study analyze "$out/votes_window.jsonl" "$out/votes_sim.jsonl" --plan "$out/plan.json" --out "$out/analysis"
