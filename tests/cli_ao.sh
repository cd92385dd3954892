#!/usr/bin/env bash
# End-to-end checks of `mrcheck render --ao ...`: every method writes ao.pfm
# through --aux, the pass list shows the AO passes (none when --ao none),
# the ground truth works, and bad AO options fail with one line on stderr.
# Usage: cli_ao.sh MRCHECK TMPDIR. Exit 77 = skipped (no GL device: mrcheck exit 69).
set -u
mr=$1
tmp=$2
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"

demo_or_exit cli_ao "$mr" "$tmp/demo"
d=$tmp/demo
r() { "$mr" render --scene "$d/scene_planned.json" --view "$d/views/view_001.json" --size 96x72 "$@"; }

for m in scheer crytek filion hbao alchemy gtao bitmask scheer-gt scheer-bm; do
  rm -rf "$tmp/aux_$m"
  if r --out "$tmp/$m.png" --ao "$m" --ao-samples 8 --aux "$tmp/aux_$m" --verbose 2>"$tmp/$m.err"; then
    [ -s "$tmp/aux_$m/ao.pfm" ] && ok || bad "--ao $m wrote no ao.pfm"
    grep -q "passes: gbuffer ao ao_blur shade" "$tmp/$m.err" && ok || bad "--ao $m pass list: $(cat "$tmp/$m.err")"
  else
    bad "--ao $m failed: $(cat "$tmp/$m.err")"
  fi
done
# issue 18 (lane ao): the depth mip chain of the slice methods is an option.
r --out "$tmp/mips.png" --ao scheer-bm --ao-mips --ao-samples 8 2>"$tmp/mips.err" && ok || bad "--ao-mips failed: $(cat "$tmp/mips.err")"
# No AO pass when AO is off; ao.pfm is then all ones (still written).
if r --out "$tmp/none.png" --ao none --aux "$tmp/aux_none" --verbose 2>"$tmp/none.err"; then
  grep -q "passes: gbuffer shade;" "$tmp/none.err" && ok || bad "--ao none ran AO: $(cat "$tmp/none.err")"
  [ -s "$tmp/aux_none/ao.pfm" ] && ok || bad "--ao none wrote no ao.pfm"
else
  bad "--ao none failed"
fi
# Options: half resolution, positions, masking, kernels, view radius.
if r --out "$tmp/opts.png" --ao scheer --ao-half --ao-positions --ao-mask on --ao-kernel poisson --ao-radii 2 \
     --ao-radius-mode view --ao-radius 0.5 --ao-c 1e7 --aux "$tmp/aux_opts" --verbose 2>"$tmp/opts.err"; then
  grep -q "passes: gbuffer ao_mask ao ao_blur ao_upsample shade" "$tmp/opts.err" && ok || bad "options pass list: $(cat "$tmp/opts.err")"
else
  bad "AO options failed: $(cat "$tmp/opts.err")"
fi
# Five radii (Doronin et al.), the stand-alone mask with its own strength,
# and the paper-pure scheer (no cosine bias, the whole-ball kernel).
for args in "--ao-radii 5" "--ao-mask standalone --ao-mask-strength 0.3" "--ao-bias 0 --ao-rmin 0 --ao-kernel uniform"; do
  # shellcheck disable=SC2086
  r --out "$tmp/more.png" --ao scheer $args 2>"$tmp/more.err" && [ -s "$tmp/more.png" ] && ok || bad "$args failed: $(cat "$tmp/more.err")"
done
# Ground truth (few rays: this is about the plumbing).
if r --out "$tmp/gt.png" --ao groundtruth --ao-radius 1 --ao-rays 8 --aux "$tmp/aux_gt" 2>"$tmp/gt.err"; then
  [ -s "$tmp/aux_gt/ao.pfm" ] && [ -s "$tmp/gt.png" ] && ok || bad "groundtruth wrote no ao.pfm"
  cmp -s "$tmp/gt.png" "$tmp/none.png" && bad "groundtruth AO did not change the shading" || ok
else
  bad "groundtruth failed: $(cat "$tmp/gt.err")"
fi
# Bad values: one line on stderr, non-zero exit, no output.
for args in "--ao ssao" "--ao scheer --ao-samples 0" "--ao scheer --ao-samples 129" "--ao scheer --ao-radius-mode far" \
            "--ao scheer --ao-mask maybe" "--ao scheer --ao-kernel sobol" "--ao scheer --ao-c -1" "--ao scheer --ao-radius 0" \
            "--ao scheer --ao-rmin 0.9 --ao-rmax 0.5" "--ao scheer --ao-radius-mode screen --ao-radius 1" \
            "--ao scheer --ao-radii 0" "--ao scheer --ao-radii 6" "--ao scheer --ao-radii -1" \
            "--ao scheer --ao-mask-strength 0.5" "--ao scheer --ao-mask standalone --ao-mask-strength 2" \
            "--ao scheer --ao-mask standalone --ao-mask-strength 0"; do
  rm -f "$tmp/bad.png"
  # shellcheck disable=SC2086
  if r --out "$tmp/bad.png" $args 2>"$tmp/bad.err"; then
    bad "accepted: $args"
  else
    [ "$(wc -l <"$tmp/bad.err")" -eq 1 ] && ok || bad "$args: not one line: $(cat "$tmp/bad.err")"
    [ ! -e "$tmp/bad.png" ] && ok || bad "$args: wrote an output"
  fi
done
# issue 18: temporal accumulation replays the shipped recording (4 tracked frames),
# gives the same first frame as without it, and --ao-thickness is range-checked.
src=$(cd "$(dirname "$0")/.." && pwd)
rp() { "$mr" replay "$src/recordings/demo" --scene "$src/configs/scenes/demo_planned.json" --from 40 --to 43 \
  --ao gtao --ao-samples 8 "$@" >/dev/null; }
if rp --out "$tmp/rp_taa" --ao-temporal 2>"$tmp/rp_taa.err" && rp --out "$tmp/rp_plain" 2>"$tmp/rp_plain.err"; then
  [ "$(find "$tmp/rp_taa" -name 'overlay_*.png' | wc -l)" -eq 4 ] && ok || bad "replay --ao-temporal: $(ls "$tmp/rp_taa")"
  first=$(find "$tmp/rp_taa" -name 'overlay_*.png' | sort | head -1)
  cmp -s "$first" "$tmp/rp_plain/$(basename "$first")" && ok || bad "replay --ao-temporal: the first frame differs from plain AO"
  last=$(find "$tmp/rp_taa" -name 'overlay_*.png' | sort | tail -1)
  cmp -s "$last" "$tmp/rp_plain/$(basename "$last")" && bad "replay --ao-temporal: the last frame did not accumulate" || ok
else
  bad "replay --ao-temporal failed: $(cat "$tmp/rp_taa.err" "$tmp/rp_plain.err")"
fi
if r --out "$tmp/thick.png" --ao bitmask --ao-thickness 0 2>"$tmp/thick.err"; then
  bad "accepted --ao-thickness 0"
else
  [ "$(wc -l <"$tmp/thick.err")" -eq 1 ] && ok || bad "--ao-thickness 0: not one line: $(cat "$tmp/thick.err")"
fi
cli_finish cli_ao
