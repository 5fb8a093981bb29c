# Sourced by the e2e scripts (`source "$(dirname "$0")/lib/prologue.sh"`): strict variables, the source and build
# trees (CGD_SOURCE_DIR and CGD_BINARY_DIR, set by CTest; else this checkout and its build/), the working directory
# at the source tree, a scratch directory $tmp removed on exit, and the fail/ok reporters counting $failures.
set -u
source_dir=${CGD_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
binary_dir=${CGD_BINARY_DIR:-$source_dir/build}
cd "$source_dir" || exit 1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0
fail() { echo "FAIL $*"; failures=$((failures + 1)); }
ok() { echo "ok   $*"; }
