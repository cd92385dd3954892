#!/usr/bin/env bash
# The shared work of `mrcheck render --views` (issue 14): with shadows, a
# rig frame draws one shadow map and culls once (--verbose reports it);
# --views-per-view-work does both per view; the outputs are there either
# way. The union volume and the shadow agreement are test_multiview_shared's.
# Usage: cli_multiview_shared.sh MRCHECK TMPDIR. Exit 77 = skipped (no GL device).
set -u
mr=$1
tmp=$2
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"
src=$(cd "$(dirname "$0")/.." && pwd)
s=$src/configs/scenes/demo_planned.json
v=$src/configs/views/demo_partition.json

"$mr" render --scene "$s" --view "$v" --out "$tmp/sh" --views 6 --size 64x48 --shadows pcf --verbose >"$tmp/sh.log" 2>&1
rc=$?
[ $rc -eq $MR_EXIT_NODEVICE ] && { echo "cli_multiview_shared: SKIPPED: no GL device: $(cat "$tmp/sh.log")"; exit 77; }
if [ $rc -eq 0 ]; then
  grep -q "6 views: [0-9]* frustum culls, 1 shadow map passes" "$tmp/sh.log" && ok || bad "shared: $(grep views: "$tmp/sh.log")"
  [ -s "$tmp/sh/view_005.png" ] && [ -s "$tmp/sh/quilt_qs3x2a1.333.png" ] && ok || bad "outputs: $(ls "$tmp/sh")"
else
  bad "render --views --shadows failed (exit $rc): $(cat "$tmp/sh.log")"
fi
"$mr" render --scene "$s" --view "$v" --out "$tmp/pv" --views 6 --size 64x48 --shadows pcf --views-per-view-work \
  --verbose >"$tmp/pv.log" 2>&1 \
  && grep -q "6 views: [0-9]* frustum culls, 6 shadow map passes" "$tmp/pv.log" && [ -s "$tmp/pv/view_005.png" ] && ok \
  || bad "per-view work: $(cat "$tmp/pv.log")"
# The culls: fewer shared than per view.
c1=$(sed -n 's/.*6 views: \([0-9]*\) frustum culls.*/\1/p' "$tmp/sh.log")
c2=$(sed -n 's/.*6 views: \([0-9]*\) frustum culls.*/\1/p' "$tmp/pv.log")
[ -n "$c1" ] && [ -n "$c2" ] && [ "$c1" -lt "$c2" ] && ok || bad "frustum culls shared $c1, per view $c2"
expect_fail per_view_alone "$tmp/b1.png" -- "$mr" render --scene "$s" --view "$v" --out "$tmp/b1.png" --views-per-view-work

cli_finish cli_multiview_shared
