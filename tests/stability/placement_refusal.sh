#!/usr/bin/env bash
# Regression test of a fixed engine bug (sim/run.cpp now places particles before writing anything).
# Scene validation accepts particles.solids_fraction < 0.64 (core/scene.cpp), the placement reaches
# 0.60 (sim/dem/placement.hpp kMaxPlacementFraction) and throws InputError above it -- but only in
# RunDriver::initial_state(), after run() has created the run directory, snapshots/ and scene.toml
# (sim/run.cpp run()). Exit status 2 must mean "nothing written" (README.md "Command lines"); here the
# directory is left behind, and the next attempt with the same -o is refused as "already holds files".
# The same holds for the other placement refusals (RSA stalled, growth not converged).
source "$(dirname "$0")/lib_stability.sh"
status=0; run place062 --set particles.solids_fraction=0.62 --set 'domain.size_dp=[12,24,12]' || status=$?
echo "  exit status $status: $(head -n 1 "$tmp/place062.err")"
[ $status -eq 2 ] || { echo "FAIL: exit status $status, expected 2"; exit 1; }
if [ -e "$tmp/place062" ]; then
  echo "FAIL: refused with status 2 but wrote $(cd "$tmp" && find place062 | tr '\n' ' ')"; exit 1
fi
echo "passed"
