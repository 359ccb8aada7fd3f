#!/usr/bin/env bash
# Configures and builds emdae with a CMake preset (default: release).
#   scripts/build.sh [release|sanitize|debug]
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${1:-release}"
cmake --preset "$preset" >/dev/null
cmake --build --preset "$preset" -j "$(nproc)"
