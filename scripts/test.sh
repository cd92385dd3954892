#!/usr/bin/env bash
# Installs dependencies, builds, and runs the whole test suite; then builds
# again with AddressSanitizer + UndefinedBehaviorSanitizer (build-asan/) and
# runs the unit and fuzz smoke tests there (MR_TEST_SANITIZE=0 leaves that
# out for a quick local run; CI runs it).
# A skipped test is a failure (scripts/ctest-strict.sh says why);
# MR_TEST_ALLOW_SKIP=1 allows skips on a machine without a GL device.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/build.sh
bash scripts/ctest-strict.sh build

if [ "${MR_TEST_SANITIZE:-1}" != 0 ]; then
  echo "test.sh: unit and fuzz smoke tests under ASan + UBSan (build-asan/)"
  mkdir -p build-asan
  cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMR_WERROR=ON -DMR_ASAN=ON -DMR_UBSAN=ON >/dev/null
  cmake --build build-asan -j"$(nproc)" >build-asan/build.log 2>&1 || { tail -n 60 build-asan/build.log; exit 1; }
  # Leak checking stays on; tests/mr_test.h explains why Mesa's driver
  # needs no suppression. UBSan findings abort (-fno-sanitize-recover).
  ASAN_OPTIONS=detect_leaks=1:check_initialization_order=1:strict_init_order=1:detect_stack_use_after_return=1 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    bash scripts/ctest-strict.sh build-asan -R '^(test_|fuzz_)'
fi
