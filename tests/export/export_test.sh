#!/usr/bin/env bash
# The exported evaluator as other codes use it (docs/export.md "Tests"; CTest label export):
#   export_test.sh write      cgd-export the shipped data/models/half_box.h5, the same with h + 0.1 (its ramp below
#                             phi_crit not 0), a --grid-table model and Radl 2014 (at the Table 1 scene's L_char)
#                             with --name model into WORK/<model>/, the points to evaluate, and the H CSV against
#                             the engine (fixture of the tests below)
#   export_test.sh c|cxx|fortran
#                             compile the header as C99 (-pedantic and more warnings as errors; with clang too where
#                             it is installed), as C++17 and C++20, or call it from Fortran
#                             through bind(C) (the module cgd-export writes + one C file with MODEL_IMPLEMENTATION);
#                             every model's values at every point against the engine's evaluator (export_check compare)
#   export_test.sh perturb    one coefficient of the half-box header changed in its 10th significant digit: the
#                             comparison must fail (the check is not vacuous)
#   export_test.sh bad_input  refusals with exit 2 and nothing written
# Environment (CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR, CGD_EXPORT_CHECK, CGD_EXPORT_CC, CGD_EXPORT_CXX, CGD_EXPORT_FC.
set -u
mode=${1:?usage: export_test.sh write|c|cxx|fortran|perturb|bad_input}
source_dir=${CGD_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
export CGD_SOURCE_DIR=$source_dir  # export_check make-shifted reads a scene from it
binary_dir=${CGD_BINARY_DIR:-$source_dir/build}
here=$source_dir/tests/export
check=${CGD_EXPORT_CHECK:-$binary_dir/tests/export/export_check}
export_tool=$binary_dir/cgd-export
work=$binary_dir/tests/export/work
models=(half_box shifted table radl2014)
failures=0
fail() { echo "FAIL $*"; failures=$((failures + 1)); }
ok() { echo "ok   $*"; }
spec() {  # the engine's model argument of export_check for a model
  case $1 in
    half_box) echo "--model $source_dir/data/models/half_box.h5" ;;
    shifted) echo "--model $work/shifted.h5" ;;
    table) echo "--model $work/table.h5" ;;
    radl2014) echo "--radl2014 $(cat "$work/radl2014/l_char_m")" ;;
  esac
}
run_consumer() {  # label exe model -> WORK/model/label.out
  "$2" <"$work/$3/points.txt" >"$work/$3/$1.out" 2>"$work/$3/$1.err" || fail "$1 ($3): exit $?: $(head -c 400 "$work/$3/$1.err")"
}

case $mode in
write)
  rm -rf "$work" && mkdir -p "$work"
  "$check" make-table "$work/table.h5" >"$work/table.log" 2>&1 || { cat "$work/table.log"; fail "make-table"; exit 1; }
  "$export_tool" "$source_dir/data/models/half_box.h5" --name model -o "$work/half_box" >"$work/half_box.log" 2>&1 ||
    fail "cgd-export half_box.h5: $(cat "$work/half_box.log")"
  # the shipped model's h with 0.1 added: its ramp below phi_crit is not 0 whatever the shipped model's h(phi_crit)
  "$check" make-shifted "$source_dir/data/models/half_box.h5" "$work/shifted.h5" >"$work/shifted.log" 2>&1 ||
    { cat "$work/shifted.log"; fail "make-shifted"; exit 1; }
  "$export_tool" "$work/shifted.h5" --name model -o "$work/shifted" >"$work/shifted_export.log" 2>&1 ||
    fail "cgd-export shifted.h5: $(cat "$work/shifted_export.log")"
  "$export_tool" "$work/table.h5" --name model -o "$work/table" >"$work/table_export.log" 2>&1 ||
    fail "cgd-export table.h5: $(cat "$work/table_export.log")"
  "$export_tool" --radl2014 --scene "$source_dir/data/scenes/table1_phi005.toml" --name model -o "$work/radl2014" \
    >"$work/radl2014.log" 2>&1 || fail "cgd-export --radl2014: $(cat "$work/radl2014.log")"
  # the L_char the header holds is the scene's (the engine is compared at the same one)
  sed -n 's/^#define CGD_MODEL_L_CHAR_M \([^ ]*\).*/\1/p' "$work/radl2014/model.h" >"$work/radl2014/l_char_m"
  for m in "${models[@]}"; do
    for f in model.h model.f90 model_pieces.csv model_H.csv; do [ -s "$work/$m/$f" ] || fail "$m: no $f"; done
    # shellcheck disable=SC2046
    "$check" points $(spec $m | cut -d' ' -f1-2 | sed 's/^--radl2014.*/--radl2014/') "$work/$m/points.txt" >/dev/null ||
      fail "$m: points"
    # shellcheck disable=SC2046
    "$check" compare $(spec $m) "$work/$m/points.txt" --csv "$work/$m/model_H.csv" || fail "$m: the H table"
  done
  grep -q "FNV-1a 64-bit checksum $(/usr/bin/python3 - "$source_dir/data/models/half_box.h5" <<'PY'
import sys
h = 14695981039346656037
for b in open(sys.argv[1], "rb").read():
    h = ((h ^ b) * 1099511628211) % 2**64
print(f"{h:016x}")
PY
)" "$work/half_box/model.h" && ok "half_box header: provenance names the file's FNV-1a checksum" ||
    fail "half_box header: no (or a wrong) checksum"
  for key in "calibrated Delta" "phi range" "resolved_runs" "filtered file"; do
    grep -q "$key" "$work/half_box/model.h" || fail "half_box header: no '$key' in the provenance"
  done
  grep -q "curves: table" "$work/table/model.h" || fail "table header: not a table model"
  grep -q "^S_h,0.016," "$work/half_box/model_pieces.csv" || fail "half_box pieces: the first S_h row does not start at phi_crit"
  # Radl 2014's local form is the published table itself
  grep -E '^(a|h),' "$source_dir/data/reference/radl2014-filtered-drag.csv" >"$work/ref.csv"
  grep -E '^(a|h),' "$work/radl2014/model_pieces.csv" >"$work/got.csv"
  /usr/bin/python3 - "$work/ref.csv" "$work/got.csv" <<'PY' && ok "radl2014 pieces = data/reference/radl2014-filtered-drag.csv" || fail "radl2014 pieces differ from the reference CSV"
import sys
ref, got = (sorted((c[0],) + tuple(float(x) for x in c[1:]) for c in (l.strip().split(",") for l in open(p) if l.strip()))
            for p in sys.argv[1:])
sys.exit(0 if ref == got and len(ref) == 15 else 1)
PY
  ;;
c | cxx | fortran)
  cc=${CGD_EXPORT_CC:-cc} cxx=${CGD_EXPORT_CXX:-c++} fc=${CGD_EXPORT_FC:-}
  # what a host code may compile with: every header must pass these without a warning
  c_warnings=(-pedantic -Wall -Wextra -Wshadow -Wconversion -Wdouble-promotion -Wstrict-prototypes -Wmissing-prototypes -Werror)
  cxx_warnings=(-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wold-style-cast -Werror)
  for m in "${models[@]}"; do
    d=$work/$m
    [ -s "$d/points.txt" ] || { fail "$m: no points (run export_test.sh write first)"; continue; }
    outs=()
    case $mode in
    c)
      $cc -std=c99 "${c_warnings[@]}" -O2 -I"$d" "$here/consumer.c" -lm -o "$d/consumer_c" 2>"$d/cc.log" ||
        { fail "$m: C99 compile: $(head -c 1500 "$d/cc.log")"; continue; }
      run_consumer c "$d/consumer_c" $m && outs+=("C=$d/c.out")
      if command -v clang >/dev/null; then  # a second compiler where there is one (not required)
        clang -std=c99 "${c_warnings[@]}" -O2 -I"$d" "$here/consumer.c" -lm -o "$d/consumer_clang" 2>"$d/clang.log" ||
          { fail "$m: clang C99 compile: $(head -c 1500 "$d/clang.log")"; continue; }
        run_consumer clang "$d/consumer_clang" $m && outs+=("C-clang=$d/clang.out")
      fi
      ;;
    cxx)
      for std in 17 20; do
        $cxx -std=c++$std "${cxx_warnings[@]}" -O2 -I"$d" "$here/consumer.cpp" -o "$d/consumer_cxx$std" 2>"$d/cxx.log" ||
          { fail "$m: C++$std compile: $(head -c 1500 "$d/cxx.log")"; continue; }
        run_consumer cxx$std "$d/consumer_cxx$std" $m && outs+=("C++$std=$d/cxx$std.out")
      done
      ;;
    fortran)
      [ -n "$fc" ] || { fail "no Fortran compiler (gfortran: scripts/setup.sh installs it)"; exit 1; }
      ( cd "$d" &&
        $cc -std=c99 "${c_warnings[@]}" -O2 -I"$d" -c "$here/impl.c" -o impl.o &&
        $fc -std=f2008 -Wall -Werror -O2 -c model.f90 -o model_mod.o &&
        $fc -std=f2008 -Wall -Werror -O2 "$here/consumer.f90" model_mod.o impl.o -lm -o consumer_f ) >"$d/fc.log" 2>&1 ||
        { fail "$m: Fortran build: $(head -c 1500 "$d/fc.log")"; continue; }
      run_consumer fortran "$d/consumer_f" $m && outs+=("Fortran=$d/fortran.out")
      ;;
    esac
    [ ${#outs[@]} -gt 0 ] || continue
    echo "---- $m"
    # shellcheck disable=SC2046
    "$check" compare $(spec $m) "$d/points.txt" "${outs[@]}" || fail "$m: $mode against the engine"
  done
  ;;
perturb)
  d=$work/half_box p=$work/perturbed
  rm -rf "$p" && mkdir -p "$p" && cp "$d/points.txt" "$p/"
  # the c0 of the 5th row of the h table, times (1 + 1e-9)
  /usr/bin/python3 - "$d/model.h" "$p/model.h" <<'PY' || { fail "could not perturb the header"; exit 1; }
import re, sys
text = open(sys.argv[1]).read()
start = text.index("cgd_model_h_pieces[")
rows = [m for m in re.finditer(r"\{([^{}]*)\},\n", text[start:])]
row = rows[4]
cells = row.group(1).split(", ")
cells[3] = repr(float(cells[3]) * (1 + 1e-9))
a, b = start + row.start(1), start + row.end(1)
open(sys.argv[2], "w").write(text[:a] + ", ".join(cells) + text[b:])
PY
  ${CGD_EXPORT_CC:-cc} -std=c99 -O2 -I"$p" "$here/consumer.c" -lm -o "$p/consumer_c" || { fail "compile perturbed"; exit 1; }
  "$p/consumer_c" <"$p/points.txt" >"$p/c.out"
  # shellcheck disable=SC2046
  if "$check" compare $(spec half_box) "$p/points.txt" "C-perturbed=$p/c.out" >"$p/compare.log" 2>&1; then
    cat "$p/compare.log"; fail "a coefficient changed by 1e-9 (relative) passed the comparison"
  else
    grep "C-perturbed" "$p/compare.log" | head -n 2
    ok "a coefficient changed by 1e-9 (relative) fails the comparison"
  fi
  ;;
bad_input)
  t=$(mktemp -d) && trap 'rm -rf "$t"' EXIT
  expect_bad() {  # label, a word the message must hold, args...
    local label=$1 word=$2; shift 2
    "$export_tool" "$@" >"$t/out" 2>"$t/err"; local s=$?
    if [ $s -ne 2 ]; then fail "$label: exit $s, expected 2: $(cat "$t/err")"
    elif ! grep -qF -- "$word" "$t/err"; then fail "$label: the message does not name '$word': $(cat "$t/err")"
    else ok "$label: exit 2, '$(head -c 160 "$t/err" | tr '\n' ' ')'"; fi
  }
  expect_bad "missing model file" "$t/none.h5" "$t/none.h5" -o "$t/o1"
  printf 'not hdf5' >"$t/junk.h5"
  expect_bad "not an HDF5 file" "$t/junk.h5" "$t/junk.h5" -o "$t/o2"
  /usr/bin/python3 -c 'import h5py, sys; f = h5py.File(sys.argv[1], "w"); f.attrs["cgd_format"] = "filtered"; f.attrs["cgd_format_version"] = 1' "$t/filtered.h5"
  expect_bad "another cgd file is not a model" "drag_model" "$t/filtered.h5" -o "$t/o3"
  expect_bad "model and --radl2014" "exactly one" "$work/table.h5" --radl2014 -o "$t/o3"
  expect_bad "--radl2014 without L_char" "--scene" --radl2014 -o "$t/o4"
  expect_bad "--l-char-m <= 0" "--l-char-m" --radl2014 --l-char-m -1 -o "$t/o5"
  expect_bad "bad --name" "--name" "$source_dir/data/models/half_box.h5" --name 9x -o "$t/o6"
  expect_bad "bad scene key" "particles.nonsense" --radl2014 --scene "$source_dir/data/scenes/table1_phi005.toml" --set particles.nonsense=1 -o "$t/o7"
  mkdir -p "$t/full" && : >"$t/full/half_box.h"
  expect_bad "existing output" "--force" "$source_dir/data/models/half_box.h5" -o "$t/full"
  expect_bad "-o is a file" "not a directory" "$source_dir/data/models/half_box.h5" -o "$t/junk.h5"
  left=$(ls "$t" | grep -v -e '^out$' -e '^err$' -e '^junk.h5$' -e '^filtered.h5$' -e '^full$' | tr '\n' ' ')
  [ -z "$left" ] && [ "$(ls "$t/full")" = "half_box.h" ] && ok "nothing written by a refused export" || fail "written by refused exports: $left $(ls "$t/full")"
  "$export_tool" --help >"$t/help" 2>&1 && grep -q "Examples:" "$t/help" && grep -q "cgd-export data/models/half_box.h5" "$t/help" &&
    ok "--help shows the examples" || fail "--help: $(head -c 300 "$t/help")"
  ;;
*) echo "unknown mode $mode"; exit 2 ;;
esac
[ $failures -eq 0 ] || { echo "$failures failure(s)"; exit 1; }
