#!/usr/bin/env bash
# End-to-end checks of --shadows on render and replay, the scene config's
# lights with size and receivers, and bad input (one line on stderr, a
# non-zero exit, no output file left behind).
# Usage: cli_shadows.sh MRCHECK TMPDIR. Exit 77 = skipped (no GL device).
set -u
mr=$1
tmp=$2
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"
src=$(cd "$(dirname "$0")/.." && pwd)
s=$src/configs/scenes/demo_planned.json
v=$src/configs/views/demo_overview.json

# PCSS on the demo hall: the pass list and shadow.pfm.
"$mr" render --scene "$s" --view "$v" --out "$tmp/pcss.png" --size 160x120 --shadows pcss --aux "$tmp/aux" \
  --verbose 2>"$tmp/pcss.err"
if need_device $? "$tmp/pcss.err" "render --shadows pcss"; then
  grep -q "passes: gbuffer shadow_map shadow shade;" "$tmp/pcss.err" && ok || bad "pass list: $(cat "$tmp/pcss.err")"
  [ -s "$tmp/aux/shadow.pfm" ] && ok || bad "--aux wrote no shadow.pfm"
  # Off by default: no shadow pass, and a different picture than with shadows.
  "$mr" render --scene "$s" --view "$v" --out "$tmp/off.png" --size 160x120 --verbose 2>"$tmp/off.err" \
    && grep -q "passes: gbuffer shade;" "$tmp/off.err" && ok || bad "default pass list: $(cat "$tmp/off.err")"
  cmp -s "$tmp/off.png" "$tmp/pcss.png" && bad "shadows changed nothing" || ok
  # The scene config turns shadows on by itself; the flag overrides it.
  printf '{"demo": "planned", "shadows": "pcss", "receivers": ["Floor*"], "lights": [{"direction": [0.4, 1, 0.25], "color": [0.55, 0.55, 0.52], "angle": 2}, {"direction": [-0.5, 0.3, -0.7], "color": [0.18, 0.19, 0.22], "shadows": false}]}\n' >"$tmp/lit.json"
  "$mr" render --scene "$tmp/lit.json" --view "$v" --out "$tmp/lit.png" --size 160x120 --verbose 2>"$tmp/lit.err" \
    && grep -q "shadow_map shadow shade" "$tmp/lit.err" && ok || bad "config 'shadows': $(cat "$tmp/lit.err")"
  cmp -s "$tmp/lit.png" "$tmp/pcss.png" && ok || bad "the config's lights and pcss differ from the default sun's"
  "$mr" render --scene "$tmp/lit.json" --view "$v" --out "$tmp/lit_off.png" --size 160x120 --shadows off --verbose \
    2>"$tmp/lit_off.err" && grep -q "passes: gbuffer shade;" "$tmp/lit_off.err" && ok || bad "--shadows off over the config"
  # Backprojection: its depth pyramid runs after the map (and for bp only).
  "$mr" render --scene "$s" --view "$v" --out "$tmp/bp.png" --size 160x120 --shadows bp --verbose 2>"$tmp/bp.err" \
    && grep -q "passes: gbuffer shadow_map shadow_pyramid shadow shade;" "$tmp/bp.err" && ok \
    || bad "bp pass list: $(cat "$tmp/bp.err")"
  # Replay with shadows: same frames as without, but shadowed.
  "$mr" replay "$src/recordings/demo" --scene "$s" --out "$tmp/replay" --to 0 --shadows pcf 2>"$tmp/replay.err" \
    && [ -s "$tmp/replay/overlay_000000.png" ] && ok || bad "replay --shadows pcf: $(cat "$tmp/replay.err")"
fi

# --- bad input -------------------------------------------------------------
expect_fail method "$tmp/bad1.png" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/bad1.png" --shadows soft
expect_fail mapsize "$tmp/bad2.png" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/bad2.png" --shadows pcf --shadows-map-size 10
expect_fail taps "$tmp/bad3.png" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/bad3.png" --shadows pcss --shadows-taps 0
expect_fail lightneg "$tmp/bad4.png" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/bad4.png" --shadows pcss --shadows-light-scale -1
expect_fail lightnan "$tmp/bad5.png" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/bad5.png" --shadows pcss --shadows-light-scale nan
i=0
for cfg in '{"demo": "planned", "lights": [{"direction": [0,1,0], "kind": "rect", "position": [0,4,0], "size": [-1, 1]}]}' \
           '{"demo": "planned", "lights": [{"direction": [0,1,0], "kind": "sphere", "position": [0,4,0], "size": "NaN"}]}' \
           '{"demo": "planned", "lights": [{"direction": [0,0,0]}]}' \
           '{"demo": "planned", "receivers": ["NoSuchNode"]}' \
           '{"demo": "planned", "shadows": "soft"}'; do
  i=$((i + 1))
  printf '%s\n' "$cfg" >"$tmp/badcfg$i.json"
  expect_fail "config$i" "$tmp/badcfg$i.png" -- "$mr" render --scene "$tmp/badcfg$i.json" --view "$v" --out "$tmp/badcfg$i.png"
done
expect_fail bench_count "" -- "$mr" bench shadows --first 12 --count 5 --out "$tmp/bench"
[ -e "$tmp/bench" ] && bad "bench left a folder behind" || ok

cli_finish cli_shadows
