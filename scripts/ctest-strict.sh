#!/usr/bin/env bash
# ctest-strict.sh BUILD_DIR [ctest args...]: runs ctest and fails on any
# skipped test, unless MR_TEST_ALLOW_SKIP=1.
#
# Used by scripts/test.sh after deps.sh has installed everything the tests
# need (EGL/Mesa, Xvfb, fonts, OpenCV): a test skips only when its
# capability is missing, and on such a machine a missing capability means
# something is broken (a GL context that cannot be made, a hidden EGL, ...).
# MR_TEST_ALLOW_SKIP=1 turns skipping back on, for machines that lack a
# device on purpose.
set -uo pipefail
dir=$1
shift
log=$dir/ctest.log
ctest --test-dir "$dir" --output-on-failure -j"$(nproc)" "$@" 2>&1 | tee "$log"
rc=${PIPESTATUS[0]}
[ "$rc" -eq 0 ] || exit "$rc"
# ctest lists skipped tests as "<n> - <name> (Skipped)" in its summary.
skipped=$(grep -E '^[[:space:]]*[0-9]+ - .* \(Skipped\)' "$log" || true)
[ -z "$skipped" ] && exit 0
if [ "${MR_TEST_ALLOW_SKIP:-0}" = 1 ]; then
  echo "ctest-strict: skips allowed (MR_TEST_ALLOW_SKIP=1):"
  echo "$skipped"
  exit 0
fi
echo "ctest-strict: FAILED: tests were skipped on a machine where deps.sh installed what they need" >&2
echo "$skipped" >&2
echo "ctest-strict: (each skipped test printed why above; MR_TEST_ALLOW_SKIP=1 allows skips)" >&2
exit 1
