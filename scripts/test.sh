#!/usr/bin/env bash
# Build and test cgd: scripts/setup.sh (install what is missing, build into build/), then the whole
# CTest suite (unit, mpi at 1 and 2 ranks, e2e). Extra arguments go to ctest (e.g. -L unit, -R Drag).
# Exit status: ctest's (0 all passed); 1 if setup or the build failed.
set -uo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
start=$(date +%s)
elapsed() { echo "test.sh: total time $(( $(date +%s) - start )) s" >&2; }

if ! bash "$repo/scripts/setup.sh"; then
  echo "test.sh: FAILED in setup/build (scripts/setup.sh); no tests were run" >&2
  elapsed
  exit 1
fi

# Open MPI refuses to run as root without these (CI and the Debian machines run as root).
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

ctest --test-dir "$repo/build" --output-on-failure -j2 "$@"
status=$?
if [ $status -eq 0 ]; then
  echo "test.sh: all tests passed" >&2
else
  echo "test.sh: FAILED: ctest exit status $status (failing tests listed above)" >&2
fi
elapsed
exit $status
