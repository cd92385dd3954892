#!/usr/bin/env bash
# Installs dependencies and builds mrcheck into build/ (warnings are errors).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMR_WERROR=ON >/dev/null
cmake --build build -j"$(nproc)"
