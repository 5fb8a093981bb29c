#!/usr/bin/env bash
# Install what cgd needs (Debian packages only) and build it into build/ (Release).
# usage: scripts/setup.sh [--bench] [--no-build]
#   --bench     also install the peer code for bench/peer_compare.sh (Debian package lammps -> lmp)
#   --no-build  install only; do not configure or build
# Idempotent: packages are checked with dpkg-query first, and apt-get runs only when one is missing;
# the build is incremental. Runs as root, or through sudo when not root.
# Exit status: 0 done; 1 install or build failed; 2 bad option.
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir="$repo/build"

packages=(build-essential gfortran cmake pkg-config git
          libhdf5-openmpi-dev hdf5-tools libgsl-dev libeigen3-dev libopenmpi-dev openmpi-bin
          libfftw3-dev libfftw3-mpi-dev libtomlplusplus-dev libcli11-dev libgtest-dev libbenchmark-dev
          python3 python3-h5py python3-numpy python3-matplotlib python3-scipy time)
bench_packages=(lammps)

with_bench=0
with_build=1
for arg in "$@"; do
  case $arg in
    --bench) with_bench=1 ;;
    --no-build) with_build=0 ;;
    -h|--help) sed -n '2,8s/^# \{0,1\}//p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "setup.sh: unknown option '$arg' (allowed: --bench, --no-build, --help)" >&2; exit 2 ;;
  esac
done
[ $with_bench -eq 1 ] && packages+=("${bench_packages[@]}")

say() { echo "setup.sh: $*" >&2; }

# ---- packages ---------------------------------------------------------------------------------
installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q 'install ok installed'; }

missing=()
for p in "${packages[@]}"; do installed "$p" || missing+=("$p"); done

if [ ${#missing[@]} -gt 0 ]; then
  say "installing missing Debian packages: ${missing[*]}"
  if [ "$(id -u)" -eq 0 ]; then
    as_root=()
  elif command -v sudo >/dev/null 2>&1; then
    as_root=(sudo)
  else
    say "not root and no sudo: install these packages as root, then rerun: ${missing[*]}"
    exit 1
  fi
  apt_opts=(-y -q -o DPkg::Lock::Timeout=600)
  if ! "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get "${apt_opts[@]}" update ||
     ! "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get "${apt_opts[@]}" install --no-install-recommends "${missing[@]}"; then
    say "FAILED: apt-get could not install: ${missing[*]}"
    exit 1
  fi
  still=()
  for p in "${missing[@]}"; do installed "$p" || still+=("$p"); done
  if [ ${#still[@]} -gt 0 ]; then
    say "FAILED: still not installed after apt-get: ${still[*]}"
    exit 1
  fi
else
  say "all ${#packages[@]} Debian packages already installed"
fi

[ $with_build -eq 1 ] || exit 0

# ---- build ------------------------------------------------------------------------------------
jobs=$(nproc 2>/dev/null || echo 2)
say "configuring ($build_dir, Release)"
if ! cmake -S "$repo" -B "$build_dir" -DCMAKE_BUILD_TYPE=Release; then
  say "FAILED: cmake configure (see the messages above)"
  exit 1
fi
say "building with $jobs jobs"
if ! cmake --build "$build_dir" -j"$jobs"; then
  say "FAILED: build (see the compiler errors above; rerun 'cmake --build build' to see them again)"
  exit 1
fi
say "build complete: $build_dir"
