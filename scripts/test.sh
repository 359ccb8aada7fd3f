#!/usr/bin/env bash
# On a fresh machine: installs what is missing, builds, and runs the whole
# test suite (ctest). `scripts/test.sh sanitize` does the same in the
# ASan+UBSan build. The opt-in slow studies are not part of it (ctest -L study).
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${1:-release}"
bash scripts/install-deps.sh
bash scripts/build.sh "$preset"
ctest --preset "$preset"
