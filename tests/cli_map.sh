#!/usr/bin/env bash
# End-to-end checks of `mrcheck map` on a rendered synthetic photo set
# (`mrcheck synth --map-photos`): the map against the true tag poses, the
# global adjustment against chaining, control points, a disconnected part,
# and bad input (one line on stderr, non-zero exit, no output file).
# Usage: cli_map.sh MRCHECK TMPDIR.
set -u
mr=$1
tmp=$2
rm -rf "$tmp" && mkdir -p "$tmp"
. "$(dirname "$0")/common_cli.sh"

set_dir=$tmp/set
"$mr" synth --map-photos "$set_dir" >/dev/null 2>"$tmp/synth.err" && ok || bad "synth --map-photos: $(cat "$tmp/synth.err")"
[ "$(ls "$set_dir/images" | wc -l)" -eq 24 ] && ok || bad "expected 24 photos"
# The true pose of tag 0 as the fixed tag's pose.
sed -n 's/.*"id":[ ]*0,[ ]*"world_from_tag":[ ]*\(\[[^]]*\]\).*/{"world_from_tag": \1}/p' \
  <(tr -d '\n\t ' <"$set_dir/truth.json" | sed 's/},{/}\n{/g') | head -1 >"$tmp/fix.json"
grep -q world_from_tag "$tmp/fix.json" && ok || bad "could not take tag 0's pose from truth.json"

common=(--images "$set_dir/images" --camera "$set_dir/camera.json" --tag-size 0.25)
"$mr" map "${common[@]}" --fix 0 --fix-pose "$tmp/fix.json" --out "$tmp/ours.json" >"$tmp/ours.out" 2>"$tmp/ours.err" \
  && ok || bad "map --fix: $(cat "$tmp/ours.err")"
grep -q "mapped 10 tags" "$tmp/ours.out" && ok || bad "map --fix: $(cat "$tmp/ours.out")"
"$mr" map "${common[@]}" --fix 0 --fix-pose "$tmp/fix.json" --chain --out "$tmp/chain.json" >/dev/null 2>&1 \
  && ok || bad "map --chain failed"
"$mr" map "${common[@]}" --control "$set_dir/control.json" --out "$tmp/ctl.json" >"$tmp/ctl.out" 2>&1 \
  && ok || bad "map --control: $(cat "$tmp/ctl.out")"
grep -q "control P4: residual" "$tmp/ctl.out" && grep -q "left out" "$tmp/ctl.out" && ok || bad "control residuals missing"
# The written map is a marker map the tracker reads, with the evidence.
"$mr" track --input "$set_dir/images/photo_000.png" --camera "$set_dir/camera.json" --markers "$tmp/ours.json" \
  >/dev/null 2>&1 && ok || bad "track cannot read the written map"
for k in sigma_pos_mm sigma_deg covariance rms_px unconnected control_points; do
  grep -q "\"$k\"" "$tmp/ctl.json" && ok || bad "no $k in the written map"
done
if command -v python3 >/dev/null 2>&1; then
  python3 - "$set_dir/truth.json" "$tmp/ours.json" "$tmp/chain.json" "$tmp/ctl.json" >"$tmp/err.txt" <<'PY'
import json, math, sys
t = {x["id"]: x["world_from_tag"] for x in json.load(open(sys.argv[1]))["tags"]}
for f in sys.argv[2:]:
    e = [math.dist([a[3], a[7], a[11]], [t[x["id"]][3], t[x["id"]][7], t[x["id"]][11]])
         for x in json.load(open(f))["tags"] for a in [x["world_from_tag"]]]
    print(1e3 * math.sqrt(sum(d * d for d in e) / len(e)))
PY
  read -r e_ours e_chain e_ctl < <(tr '\n' ' ' <"$tmp/err.txt")
  echo "map error RMS: ours ${e_ours} mm, chaining ${e_chain} mm, control points ${e_ctl} mm"
  awk -v a="$e_ours" -v b="$e_chain" 'BEGIN { exit !(a < 60 && b > 3 * a) }' && ok || bad "ours $e_ours mm vs chaining $e_chain mm"
  awk -v a="$e_ctl" 'BEGIN { exit !(a < 20) }' && ok || bad "control-point map $e_ctl mm off"
fi

# issue 15: the same photos as a video (`--video`), and a camera file 4 %
# off in focal length, refined (`--refine-intrinsics`).
[ -s "$set_dir/photos.avi" ] && ok || bad "synth --map-photos wrote no photos.avi"
"$mr" map --video "$set_dir/photos.avi" --camera "$set_dir/camera.json" --tag-size 0.25 --fix 0 --fix-pose "$tmp/fix.json" \
  --out "$tmp/video.json" >"$tmp/video.out" 2>"$tmp/video.err" && ok || bad "map --video: $(cat "$tmp/video.err")"
grep -q "mapped 10 tags" "$tmp/video.out" && ok || bad "map --video: $(cat "$tmp/video.out")"
sed 's/"fx":[[:space:]]*\([0-9.e+-]*\)/"fx": FX(\1)/; s/"fy":[[:space:]]*\([0-9.e+-]*\)/"fy": FY(\1)/' "$set_dir/camera.json" |
  awk '{ while (match($0, /F[XY]\([0-9.e+-]*\)/)) { v = substr($0, RSTART + 3, RLENGTH - 4); $0 = substr($0, 1, RSTART - 1) sprintf("%.6f", v * 1.04) substr($0, RSTART + RLENGTH) } print }' \
  >"$tmp/camera_off.json"
grep -q '"fx"' "$tmp/camera_off.json" && ! cmp -s "$tmp/camera_off.json" "$set_dir/camera.json" && ok || bad "could not write the 4 % off camera"
off=(--images "$set_dir/images" --camera "$tmp/camera_off.json" --tag-size 0.25 --fix 0 --fix-pose "$tmp/fix.json")
"$mr" map "${off[@]}" --out "$tmp/off.json" >/dev/null 2>"$tmp/off.err" && ok || bad "map with the off camera: $(cat "$tmp/off.err")"
"$mr" map "${off[@]}" --refine-intrinsics --out "$tmp/refined.json" >/dev/null 2>"$tmp/refined.err" \
  && ok || bad "map --refine-intrinsics: $(cat "$tmp/refined.err")"
if command -v python3 >/dev/null 2>&1; then
  python3 - "$set_dir/truth.json" "$set_dir/camera.json" "$tmp/video.json" "$tmp/off.json" "$tmp/refined.json" >"$tmp/vr.txt" <<'PY'
import json, math, sys
t = {x["id"]: x["world_from_tag"] for x in json.load(open(sys.argv[1]))["tags"]}
def err(f):
    e = [math.dist([a[3], a[7], a[11]], [t[x["id"]][3], t[x["id"]][7], t[x["id"]][11]])
         for x in json.load(open(f))["tags"] for a in [x["world_from_tag"]]]
    return 1e3 * math.sqrt(sum(d * d for d in e) / len(e))
fx = json.load(open(sys.argv[2]))["fx"]
ref = json.load(open(sys.argv[5]))["map"]["camera"]["fx"]
print(err(sys.argv[3]), err(sys.argv[4]), err(sys.argv[5]), fx, ref)
PY
  read -r e_video e_off e_ref fx_true fx_ref < <(tr '\n' ' ' <"$tmp/vr.txt")
  echo "map --video error RMS ${e_video} mm; camera 4 % off: ${e_off} mm, refined: ${e_ref} mm (fx ${fx_ref}, true ${fx_true})"
  awk -v a="$e_video" -v b="$e_ours" 'BEGIN { exit !(a < 60 && a < 2 * b + 5) }' && ok || bad "map --video $e_video mm (photos: $e_ours mm)"
  # 24 photos with ~2.5 tags each pin the focal length down only weakly (with
  # exact corners too: 260 -> 256 here, 251 with 100 photos; test_map checks
  # a set that determines it): refining must move it towards the truth and
  # not make the map worse.
  awk -v a="$e_ref" -v b="$e_off" 'BEGIN { exit !(a < b) }' && ok || bad "refined $e_ref mm vs off $e_off mm"
  awk -v r="$fx_ref" -v t="$fx_true" 'BEGIN { d = r / t - 1; exit !(d < 0.035 && d > -0.035) }' && ok || bad "refined fx $fx_ref, true $fx_true"
fi
printf 'not a video' >"$tmp/bad.avi"
expect_fail bad_video "$tmp/x.json" -- "$mr" map --video "$tmp/bad.avi" --camera "$set_dir/camera.json" --tag-size 0.25 --fix 0 --out "$tmp/x.json"
expect_fail images_and_video "$tmp/x.json" -- "$mr" map --images "$set_dir/images" --video "$set_dir/photos.avi" --camera "$set_dir/camera.json" --tag-size 0.25 --fix 0 --out "$tmp/x.json"

# Bad input of issue 15 (Must have 5): one photo; NaN in the camera, the
# fixed pose, a tag size; a control point 30 cm off (more than 5 sigma) is
# named as an outlier and left out, the map still written (30 cm: with four
# points on this small set the leave-one-out sigma is ~30 mm, so 5 cm hides).
mkdir -p "$tmp/one" && cp "$set_dir/images/photo_000.png" "$tmp/one/"
expect_fail one_photo "$tmp/x.json" -- "$mr" map --images "$tmp/one" --camera "$set_dir/camera.json" --tag-size 0.25 --fix 0 --out "$tmp/x.json"
grep -q "two or more photos" "$tmp/one_photo.err" && ok || bad "one photo: $(cat "$tmp/one_photo.err")"
sed 's/"fx":[^,]*/"fx": NaN/' "$set_dir/camera.json" >"$tmp/cam_nan.json"
expect_fail nan_camera "$tmp/x.json" -- "$mr" map --images "$set_dir/images" --camera "$tmp/cam_nan.json" --tag-size 0.25 --fix 0 --out "$tmp/x.json"
printf '{"world_from_tag": [1,0,0,NaN, 0,1,0,0, 0,0,1,0, 0,0,0,1]}' >"$tmp/nanfix.json"
expect_fail nan_fix_pose "$tmp/x.json" -- "$mr" map "${common[@]}" --fix 0 --fix-pose "$tmp/nanfix.json" --out "$tmp/x.json"
expect_fail nan_tag_size "$tmp/x.json" -- "$mr" map "${common[@]}" --tag-sizes 3=nan --fix 0 --out "$tmp/x.json"
if command -v python3 >/dev/null 2>&1; then
  python3 - "$set_dir/control.json" "$tmp/ctl_off.json" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))
c["points"][1]["xyz"][1] += 0.30  # 30 cm: beyond 5 sigma of the leave-one-out check (about 30 mm here)
json.dump(c, open(sys.argv[2], "w"))
PY
  "$mr" map "${common[@]}" --control "$tmp/ctl_off.json" --out "$tmp/ctl_off_map.json" >"$tmp/ctl_off.out" 2>&1 \
    && ok || bad "map with an outlying control point failed: $(cat "$tmp/ctl_off.out")"
  grep -q "control point P2 disagrees by .* sigma: left out" "$tmp/ctl_off.out" && ok || bad "outlier not named: $(cat "$tmp/ctl_off.out")"
  [ -s "$tmp/ctl_off_map.json" ] && ok || bad "no map written with an outlier"
fi

# A disconnected part: photos of tags 0..2 and, apart, of the others would
# need another set; a fixed tag that is never seen is the bad-input case.
expect_fail unseen_fix "$tmp/x.json" -- "$mr" map "${common[@]}" --fix 77 --out "$tmp/x.json"
mkdir -p "$tmp/empty"
expect_fail no_gauge "$tmp/x.json" -- "$mr" map "${common[@]}" --out "$tmp/x.json"
expect_fail both_gauges "$tmp/x.json" -- "$mr" map "${common[@]}" --fix 0 --control "$set_dir/control.json" --out "$tmp/x.json"
expect_fail no_images "$tmp/x.json" -- "$mr" map --images "$tmp/empty" --camera "$set_dir/camera.json" --tag-size 0.25 --fix 0 --out "$tmp/x.json"
expect_fail bad_sizes "$tmp/x.json" -- "$mr" map "${common[@]}" --tag-sizes 3=-1 --fix 0 --out "$tmp/x.json"
printf '{"points": [{"name": "A", "tag": 0, "xyz": [0, 0, 0]}, {"name": "B", "tag": 1, "xyz": [1, 0, 0]}]}' >"$tmp/two.json"
expect_fail two_controls "$tmp/x.json" -- "$mr" map "${common[@]}" --control "$tmp/two.json" --out "$tmp/x.json"
printf '{"points": [{"name": "A", "tag": 0, "xyz": [0, NaN, 0]}]}' >"$tmp/nan.json"
expect_fail nan_control "$tmp/x.json" -- "$mr" map "${common[@]}" --control "$tmp/nan.json" --out "$tmp/x.json"
printf '{"world_from_tag": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,2]}' >"$tmp/badfix.json"
expect_fail bad_fix_pose "$tmp/x.json" -- "$mr" map "${common[@]}" --fix 0 --fix-pose "$tmp/badfix.json" --out "$tmp/x.json"
expect_fail unknown_size "$tmp/x.json" -- "$mr" map --images "$set_dir/images" --camera "$set_dir/camera.json" --tag-sizes 99=0.2 --fix 0 --out "$tmp/x.json"

# measure: a tag corner of the shipped recording tapped where the detector
# found it, in frames far apart, against the corner's mapped position.
src=$(cd "$(dirname "$0")/.." && pwd)
rec=$src/recordings/demo
if command -v python3 >/dev/null 2>&1; then
  python3 - "$rec" "$tmp" <<'PY'
import json, sys
rec, tmp = sys.argv[1], sys.argv[2]
meta = json.load(open(rec + "/meta.json"))
frames = [json.loads(l) for l in open(rec + "/frames.jsonl") if l.strip()]
best = None
for tag in meta["markers"]["tags"]:
    seen = [f for f in frames if f["pose"]["valid"] and any(d["id"] == tag["id"] for d in f["detections"])]
    if len(seen) >= 3 and (best is None or len(seen) > len(best[1])):
        best = (tag, seen)
tag, seen = best
pick = [seen[0], seen[len(seen) // 2], seen[-1]]
taps = [{"frame": f["frame"], "px": [d["corners"][0] for d in f["detections"] if d["id"] == tag["id"]][0]} for f in pick]
s = meta["markers"]["tag_size"] / 2
m = tag["world_from_tag"]
corner = [m[4 * r] * -s + m[4 * r + 1] * s + m[4 * r + 3] for r in range(3)]  # corner 0: (-s/2, +s/2)
json.dump({"taps": taps, "planned": corner}, open(tmp + "/obs.json", "w"))
json.dump({"taps": [taps[0], taps[0]], "planned": corner}, open(tmp + "/same.json", "w"))
json.dump({"taps": [taps[0], {"frame": 99999, "px": [1, 2]}]}, open(tmp + "/noframe.json", "w"))
PY
  "$mr" measure --recording "$rec" --observations "$tmp/obs.json" --out "$tmp/measured.json" >"$tmp/measure.out" 2>&1 \
    && ok || bad "measure: $(cat "$tmp/measure.out")"
  cat "$tmp/measure.out"
  grep -q "distance to the planned point: .* mm +- .* mm" "$tmp/measure.out" && ok || bad "measure printed no distance"
  grep -q '"distance_sigma_mm"' "$tmp/measured.json" && ok || bad "measure wrote no result"
  # The verdict against DIN 18202 (the default) and against a hall's table.
  grep -Eq "^verdict: (within tolerance|out of tolerance|undecided): .* limit ±[0-9]+ mm \(DIN 18202 Table 1, " \
    "$tmp/measure.out" && ok || bad "measure printed no verdict"
  grep -Eq '"verdict":[[:space:]]*"(within|out|undecided)"' "$tmp/measured.json" && ok || bad "measure wrote no verdict"
  printf '{"default_mm": 5000}' >"$tmp/wide_tol.json"
  "$mr" measure --recording "$rec" --observations "$tmp/obs.json" --tolerances "$tmp/wide_tol.json" >"$tmp/wide.out" 2>&1
  grep -q "^verdict: within tolerance: .* limit ±5000 mm (hall table, default)" "$tmp/wide.out" \
    && ok || bad "measure --tolerances: $(cat "$tmp/wide.out")"
  printf '{"default_mm": -5}' >"$tmp/bad_tol.json"
  expect_fail measure_bad_tolerances "$tmp/m4.json" -- "$mr" measure --recording "$rec" --observations "$tmp/obs.json" \
    --tolerances "$tmp/bad_tol.json" --out "$tmp/m4.json"
  # issue 15: against the planned surface (the nearest point of the model).
  "$mr" measure --recording "$rec" --observations "$tmp/obs.json" --scene "$src/configs/scenes/demo_planned.json" \
    --out "$tmp/surface.json" >"$tmp/surface.out" 2>&1 && ok || bad "measure --scene: $(cat "$tmp/surface.out")"
  cat "$tmp/surface.out"
  grep -q "distance to the planned surface: .* mm +- .* mm (1 sigma), nearest point .* on " "$tmp/surface.out" \
    && ok || bad "measure --scene printed no surface distance"
  grep -q '"surface_distance_sigma_mm"' "$tmp/surface.json" && grep -q '"nearest_node"' "$tmp/surface.json" \
    && ok || bad "measure --scene wrote no surface distance"
  expect_fail measure_bad_scene "$tmp/m3.json" -- "$mr" measure --recording "$rec" --observations "$tmp/obs.json" \
    --scene "$tmp/no_such_scene.glb" --out "$tmp/m3.json"
  expect_fail measure_same_pose "$tmp/m2.json" -- "$mr" measure --recording "$rec" --observations "$tmp/same.json" --out "$tmp/m2.json"
  grep -q "baseline angle" "$tmp/measure_same_pose.err" && ok || bad "same pose: $(cat "$tmp/measure_same_pose.err")"
  expect_fail measure_no_frame "$tmp/m2.json" -- "$mr" measure --recording "$rec" --observations "$tmp/noframe.json" --out "$tmp/m2.json"
fi
# NaN in the recording: its camera (meta.json), a tapped frame's pose (frames.jsonl).
if [ -f "$tmp/obs.json" ]; then
  mkdir -p "$tmp/rec_nan_meta" "$tmp/rec_nan_pose"
  sed 's/"fx":[^,]*/"fx": NaN/' "$rec/meta.json" >"$tmp/rec_nan_meta/meta.json"
  cp "$rec/frames.jsonl" "$tmp/rec_nan_meta/"
  expect_fail measure_nan_meta "$tmp/m2.json" -- "$mr" measure --recording "$tmp/rec_nan_meta" --observations "$tmp/obs.json" --out "$tmp/m2.json"
  cp "$rec/meta.json" "$tmp/rec_nan_pose/"
  f0=$(sed -n 's/.*"taps": *\[{"frame": *\([0-9]*\).*/\1/p' "$tmp/obs.json")
  sed "/\"frame\": *$f0,/s/\"world_from_camera\": *\[/\"world_from_camera\": [NaN, /" "$rec/frames.jsonl" >"$tmp/rec_nan_pose/frames.jsonl"
  grep -q NaN "$tmp/rec_nan_pose/frames.jsonl" && ok || bad "could not put a NaN into frame $f0's pose"
  # The reader warns about the line it skipped, then the tap fails on it.
  "$mr" measure --recording "$tmp/rec_nan_pose" --observations "$tmp/obs.json" --out "$tmp/m2.json" >/dev/null 2>"$tmp/nanpose.err"
  rc=$?
  [ $rc -ne 0 ] && [ $rc -lt 128 ] && [ ! -e "$tmp/m2.json" ] && tail -1 "$tmp/nanpose.err" | grep -q "frame $f0 is not in the recording (its frames.jsonl has unreadable lines" \
    && ok || bad "NaN pose: rc $rc: $(cat "$tmp/nanpose.err")"
fi
printf '{"taps": [{"frame": 0, "px": [NaN, 1]}]}' >"$tmp/nan_obs.json"
expect_fail measure_nan "$tmp/m2.json" -- "$mr" measure --recording "$rec" --observations "$tmp/nan_obs.json" --out "$tmp/m2.json"
expect_fail measure_no_args "" -- "$mr" measure --recording "$rec"

cli_finish cli_map
