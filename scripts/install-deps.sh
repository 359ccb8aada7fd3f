#!/usr/bin/env bash
# Installs, from Debian's packages, whatever emdae needs and the machine lacks.
# Safe to run repeatedly: it does nothing when everything is there.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libsundials-dev libeigen3-dev libsuitesparse-dev libgsl-dev
  libtomlplusplus-dev libcli11-dev libfmt-dev nlohmann-json3-dev zlib1g-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-meshio python3-numpy gnuplot-nox
  python3-dev pybind11-dev python3-pytest python3-matplotlib
  libopenmpi-dev openmpi-bin
  # OpenBLAS (serial: studies run their own processes) under UMFPACK's dense
  # fronts; Debian's alternatives point libblas.so.3 at it. From 10^4 flops
  # per unknown UMFPACK then factors 1.3-3.6x faster than KLU refactors, and
  # the bearings run 1.16-1.32x faster on it (docs/performance.md §11).
  libopenblas0-serial
)
if [[ "${EMDAE_BROWSER_TESTS:-1}" == 1 ]]; then packages+=(chromium); fi
# VTK's own reader (ParaView's) for the VTU tests (tests/test_report.cpp; ~230 MB).
if [[ "${EMDAE_VTK_TESTS:-1}" == 1 ]]; then packages+=(python3-vtk9); fi
# GetFEM for bench/ring_vs_getfem.py (the side-by-side timing of issue 14): on request.
if [[ "${EMDAE_GETFEM:-0}" == 1 ]]; then packages+=(python3-getfem); fi
# The fuzz targets (fuzz/, cmake --preset fuzz): clang with libFuzzer.
if [[ "${EMDAE_FUZZ:-0}" == 1 ]]; then packages+=(clang-14 libclang-rt-14-dev); fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

echo "emdae: installing ${missing[*]}" >&2
SUDO=""
[[ $(id -u) -ne 0 ]] && SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
