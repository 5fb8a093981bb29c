#!/usr/bin/env bash
# e2e: cgd-fit refuses bad input the way README.md "Command lines" says: exit status 2, a message on
# stderr naming the file and the key, and nothing written (the -o model file does not exist afterwards).
# Also: a good file is fitted (exit 0, model written), --help/--version exit 0, and cgd-generate refuses
# the filtered laws (a resolved run uses a microscopic law) and a drag model file that does not exist.
#
# Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR.
set -u

source_dir=${CGD_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
binary_dir=${CGD_BINARY_DIR:-$source_dir/build}
fit=$binary_dir/cgd-fit
generate=$binary_dir/cgd-generate
if [ ! -x "$fit" ]; then
  echo "SKIP: $fit not built"
  exit 0
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0
make() { /usr/bin/python3 "$source_dir/tests/fit/make_synthetic_filtered.py" --snapshots 20 --block 5 "$@"; }

# expect_bad NAME EXPECTED_SUBSTRING... -- ARGS...: cgd-fit ARGS -o $tmp/model.h5 exits 2, prints every
# substring on stderr and leaves no $tmp/model.h5 (nor a temporary file beside it).
expect_bad() {
  local name=$1; shift
  local expected=()
  while [ "$1" != "--" ]; do expected+=("$1"); shift; done
  shift
  rm -f "$tmp"/model.h5*
  "$fit" "$@" -o "$tmp/model.h5" >"$tmp/stdout" 2>"$tmp/stderr"
  local status=$? ok=1
  [ "$status" -eq 2 ] || { echo "FAIL $name: exit status $status, expected 2"; ok=0; }
  for e in "${expected[@]}"; do
    grep -qF -- "$e" "$tmp/stderr" || { echo "FAIL $name: stderr lacks \"$e\""; ok=0; }
  done
  if ls "$tmp"/model.h5* >/dev/null 2>&1; then echo "FAIL $name: something was written"; ok=0; fi
  if [ $ok -eq 1 ]; then echo "ok   $name: $(head -n 1 "$tmp/stderr" | cut -c1-200)"
  else sed 's/^/     /' "$tmp/stderr"; failures=$((failures + 1)); fi
}

make -o "$tmp/good.h5" --seed 1 && make -o "$tmp/good2.h5" --seed 2 &&
  make -o "$tmp/snapshot.h5" --format snapshot && make -o "$tmp/wenyu.h5" --micro-drag wen-yu &&
  make -o "$tmp/thick.h5" --diameter 100e-6 && make -o "$tmp/two_widths.h5" --widths 2 &&
  make -o "$tmp/three_bins.h5" --bins 3 && make -o "$tmp/bare.h5" --seed 3 --no-per-snapshot ||
  { echo "FAIL: could not make the synthetic files"; exit 1; }

expect_bad missing-file        "$tmp/nope.h5"                                    -- "$tmp/nope.h5"
expect_bad not-filtered        "$tmp/snapshot.h5" "cgd_format" "not a filtered file" -- "$tmp/snapshot.h5"
expect_bad other-law-pooled    "$tmp/wenyu.h5" "micro_drag" "different physics"   -- "$tmp/good.h5" "$tmp/wenyu.h5"
expect_bad other-size-pooled   "$tmp/thick.h5" "diameter_m"                      -- "$tmp/good.h5" "$tmp/thick.h5"
expect_bad too-few-widths      "$tmp/two_widths.h5" "too few filter widths"      -- "$tmp/two_widths.h5"
expect_bad too-few-bins        "$tmp/three_bins.h5" "too few phi bins"           -- "$tmp/three_bins.h5"
expect_bad bad-option          "--min-widths"                                    -- "$tmp/good.h5" --min-widths 2
expect_bad bad-width-exponent  "--width-exponent two" "(0, 10]" "fit"          -- "$tmp/good.h5" --width-exponent two
expect_bad zero-width-exponent "--width-exponent 0" "(0, 10]"                    -- "$tmp/good.h5" --width-exponent 0
expect_bad operator-no-grids   "$tmp/good.h5" "/grids" "cgd-filter --grids"      -- "$tmp/good.h5" --operator grid
expect_bad operator-unknown    "--operator tent" "box" "grid"                    -- "$tmp/good.h5" --operator tent
expect_bad grid-table-no-grid  "$tmp/good.h5" "--grid-table 4" "/grids/4"        -- "$tmp/good.h5" --grid-table 4
# --pool-runs (docs/fit.md "Pooled runs"): with a table or the parcel fit, files it cannot pool
expect_bad pool-grid-table     "--pool-runs with --grid-table"                   -- "$tmp/good.h5" "$tmp/good2.h5" --pool-runs --grid-table 4
expect_bad pool-drift-table    "--pool-runs with --drift-table"                  -- "$tmp/good.h5" "$tmp/good2.h5" --pool-runs --drift-table 4
expect_bad pool-parcel-fit     "--pool-runs with --parcel-fit"                   -- "$tmp" --pool-runs --parcel-fit "$tmp/good.h5"
expect_bad pool-no-snapshots   "$tmp/bare.h5" "per-snapshot sums"                -- "$tmp/good.h5" "$tmp/bare.h5" --pool-runs
expect_bad pool-other-widths   "$tmp/two_widths.h5" "same widths and grids" "/width_1" -- "$tmp/good.h5" "$tmp/two_widths.h5" --pool-runs
# the model file's directory does not exist: refused before the fit
status=0; "$fit" "$tmp/good.h5" -o "$tmp/no/such/dir/model.h5" >"$tmp/stdout" 2>"$tmp/stderr" || status=$?
if [ $status -eq 2 ] && grep -qF "$tmp/no/such/dir" "$tmp/stderr" && [ ! -e "$tmp/no" ]; then
  echo "ok   no-output-directory: $(head -n 1 "$tmp/stderr" | cut -c1-200)"
else
  echo "FAIL no-output-directory (status $status)"; sed 's/^/     /' "$tmp/stderr"; failures=$((failures + 1))
fi

# a good pair of files is fitted
if "$fit" "$tmp/good.h5" "$tmp/good2.h5" --bootstrap 50 -o "$tmp/model.h5" >"$tmp/stdout" 2>"$tmp/stderr" &&
   [ -s "$tmp/model.h5" ] && grep -q "cross-validation of H: rms" "$tmp/stdout"; then
  echo "ok   good-files: $(grep 'cross-validation' "$tmp/stdout")"
else
  echo "FAIL good-files"; sed 's/^/     /' "$tmp/stderr"; failures=$((failures + 1))
fi
# the same pair pooled: written, /sources says so and lists both files
if "$fit" "$tmp/good.h5" "$tmp/good2.h5" --pool-runs --bootstrap 50 -o "$tmp/pooled.h5" >"$tmp/stdout" 2>"$tmp/stderr" &&
   /usr/bin/python3 - "$tmp/pooled.h5" "$tmp/good.h5" "$tmp/good2.h5" <<'PY'
import sys, h5py
with h5py.File(sys.argv[1], "r") as f:
    s = f["sources"].attrs
    files = [x.decode() if isinstance(x, bytes) else str(x) for x in s["files"]]
    sys.exit(0 if int(s["pooled_runs"]) == 1 and files == sys.argv[2:] else 1)
PY
then
  echo "ok   good-files-pooled: $(grep 'cross-validation' "$tmp/stdout")"
else
  echo "FAIL good-files-pooled"; sed 's/^/     /' "$tmp/stderr"; failures=$((failures + 1))
fi
# an existing output: refused without --force (exit 2, the file unchanged), replaced with it
cp "$tmp/model.h5" "$tmp/model_before.h5"
status=0; "$fit" "$tmp/good.h5" --bootstrap 0 --no-cross-validation --quiet -o "$tmp/model.h5" 2>"$tmp/stderr" || status=$?
if [ $status -eq 2 ] && grep -qF -- "--force" "$tmp/stderr" && cmp -s "$tmp/model.h5" "$tmp/model_before.h5"; then
  echo "ok   existing-output: $(head -n 1 "$tmp/stderr" | cut -c1-200)"
else
  echo "FAIL existing-output (status $status)"; sed 's/^/     /' "$tmp/stderr"; failures=$((failures + 1))
fi
if "$fit" "$tmp/good.h5" --bootstrap 0 --no-cross-validation --quiet --force -o "$tmp/model.h5" 2>"$tmp/stderr" &&
   ! cmp -s "$tmp/model.h5" "$tmp/model_before.h5"; then
  echo "ok   existing-output-force"
else
  echo "FAIL existing-output-force"; sed 's/^/     /' "$tmp/stderr"; failures=$((failures + 1))
fi
# the output is one of the inputs: refused even with --force, the input untouched (it was replaced by a model)
cp "$tmp/good.h5" "$tmp/good_copy.h5"
for extra in "" --force; do
  status=0; "$fit" "$tmp/good_copy.h5" --bootstrap 0 --no-cross-validation --quiet $extra -o "$tmp/good_copy.h5" \
    2>"$tmp/stderr" || status=$?
  if [ $status -eq 2 ] && grep -qF "one of the inputs" "$tmp/stderr" && cmp -s "$tmp/good.h5" "$tmp/good_copy.h5"; then
    echo "ok   output-is-input ${extra:-(no --force)}"
  else
    echo "FAIL output-is-input ${extra:-(no --force)} (status $status)"; sed 's/^/     /' "$tmp/stderr"; failures=$((failures + 1))
  fi
done
for flag in --help --version; do
  if "$fit" $flag >"$tmp/stdout" 2>&1 && [ -s "$tmp/stdout" ]; then echo "ok   $flag"
  else echo "FAIL $flag"; failures=$((failures + 1)); fi
done

# cgd-generate: filtered laws refused (exit 2, the key named, nothing written)
if [ -x "$generate" ]; then
  base=$source_dir/data/scenes/sedimentation_demo.toml
  gen_bad() {
    local name=$1 want=$2; shift 2
    rm -rf "$tmp/run"
    "$generate" "$base" "$@" --quiet -o "$tmp/run" >"$tmp/stdout" 2>"$tmp/stderr"
    local status=$?
    if [ $status -eq 2 ] && grep -qF -- "$want" "$tmp/stderr" && [ ! -e "$tmp/run" ]; then
      echo "ok   $name: $(head -n 1 "$tmp/stderr" | cut -c1-200)"
    else
      echo "FAIL $name (status $status)"; sed 's/^/     /' "$tmp/stderr"; failures=$((failures + 1))
    fi
  }
  gen_bad generate-radl2014 "fluid.drag" --set 'fluid.drag="radl2014"'
  gen_bad generate-model "coarse-grid runs" --set 'fluid.drag="model"' --set "fluid.drag_model=\"$tmp/model.h5\""
  # (a missing model file: cgd-generate refuses the law itself before it looks for the file)
fi

[ $failures -eq 0 ] || { echo "$failures failure(s)"; exit 1; }
echo "all ok"
