#!/usr/bin/env bash
# On a fresh machine: installs what is missing, builds, and runs the default
# scene with the energy-momentum scheme; its report lands in out/default/.
# Arguments are passed to `emdae` (e.g. `scripts/run.sh run examples/bearing.toml`).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh release
exec ./build/release/cli/emdae "$@"
