#!/usr/bin/env bash
# e2e: the tools name the commit they were built from (core/version.hpp): `--version` of every executable is
# "<project version>-<git describe --always --dirty --tags>" of the source tree as it is now, so the
# code_version written into every output file is not the commit the build directory was first configured at
# (CMake ran once, then the tree moved on: the version was stale until cmake/code_version.cmake ran at every
# build). Skipped (status 0, said) when the source is not a git work tree.
# Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR.
set -u
source_dir=${CGD_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
binary_dir=${CGD_BINARY_DIR:-$source_dir/build}
failures=0
fail() { echo "FAIL $*"; failures=$((failures + 1)); }

describe=$(git -C "$source_dir" describe --always --dirty --tags 2>/dev/null) ||
  { echo "code_version: $source_dir is not a git work tree: nothing to compare"; exit 0; }
project=$(sed -n 's/^project(cgd VERSION \([0-9.]*\).*/\1/p' "$source_dir/CMakeLists.txt")
[ -n "$project" ] || fail "no project version in CMakeLists.txt"
want="$project-$describe"
for tool in cgd-generate cgd-filter cgd-fit cgd-coarse cgd-export; do
  got=$("$binary_dir/$tool" --version 2>&1) || fail "$tool --version exited with $?"
  [ "$got" = "$tool $want" ] || fail "$tool --version: '$got', want '$tool $want'"
done
[ "$failures" -eq 0 ] && echo "code_version: every tool says $want"
exit $((failures > 0))
