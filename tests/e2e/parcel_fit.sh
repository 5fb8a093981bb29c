#!/usr/bin/env bash
# e2e: cgd-fit --parcel-fit on synthetic coarse summaries (a model fitted to a synthetic filtered file):
#  * no parcel effect (every alpha at the alpha = 1 slip, within 0.3 %, three realisations each): k's interval
#    holds 0, the output's c_corr is 1 (a = k = 0, applied = 0, the fitted k in k_fit), the report says
#    "c_corr not applied" -- Makefile.pipeline then reuses the modelraw runs (tools/pipeline_reuse.py --identity);
#  * parcels that need more drag (slips rising as exp(0.05 (alpha - 1))): k < 0, applied = 1, c_corr > 1;
#  * a phi with alpha > 1 runs and no alpha = 1 run: exit 2, nothing written.
# Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR.
set -u
source_dir=${CGD_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}
binary_dir=${CGD_BINARY_DIR:-$source_dir/build}
fit=$binary_dir/cgd-fit
py=/usr/bin/python3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failures=0
fail() { echo "FAIL $*"; failures=$((failures + 1)); }
ok() { echo "ok   $*"; }
"$py" "$source_dir/tests/fit/make_synthetic_filtered.py" --snapshots 20 --block 5 -o "$tmp/filtered.h5" >/dev/null &&
  "$fit" "$tmp/filtered.h5" --bootstrap 20 --no-cross-validation -o "$tmp/model.h5" >"$tmp/fit.log" 2>&1 ||
  { cat "$tmp/fit.log"; echo "FAIL: could not make the model"; exit 1; }

# runs NAME PHI "ALPHA:SEED:SLIP ..." : synthetic summaries under $tmp/NAME/ (slips in u_t, errors 0.005)
runs() {
  local item alpha seed slip label d
  for item in $3; do
    IFS=: read -r alpha seed slip <<<"$item"
    if [ "$alpha" = 1 ]; then label=model; else label=modelraw; fi
    d=$tmp/$1/phi$2_c4_a${alpha}_${label}_s$seed
    "$py" "$source_dir/tests/fit/synthetic_summary.py" "$d" "$2" "$alpha" "$seed" "$slip" && echo "$d"
  done
}
attrs() {  # FILE: the /c_corr attributes as python literals
  "$py" -c 'import sys, h5py; a = h5py.File(sys.argv[1], "r")["c_corr"].attrs; print({k: (a[k].decode() if isinstance(a[k], bytes) else a[k]) for k in ("a", "k", "k_fit", "applied", "p_value", "decision")})' "$1"
}

# no parcel effect
mapfile -t flat < <(runs flat 0.05 "1:1:0.950 2:1:0.952 2:2:0.948 2:3:0.951 3:1:0.949 3:2:0.953 3:3:0.950 4:1:0.947 4:2:0.951 4:3:0.952")
"$fit" --parcel-fit "$tmp/model.h5" "${flat[@]}" -o "$tmp/flat.h5" >"$tmp/flat.log" 2>&1 || { cat "$tmp/flat.log"; fail "flat: exit status"; }
"$py" -c '
import sys, h5py
a = h5py.File(sys.argv[1], "r")["c_corr"].attrs
assert a["applied"] == 0 and a["a"] == 0 and a["k"] == 0, dict(a)
assert a["k_interval"][0] <= 0 <= a["k_interval"][1] and a["k_fit"] != 0
assert list(a["runs_seed"]).count(2) == 3
' "$tmp/flat.h5" && grep -q "^c_corr not applied: k's 95 % interval" "$tmp/flat.log" &&
  "$py" "$source_dir/tools/pipeline_reuse.py" --identity "$tmp/flat.h5" &&
  ok "no parcel effect: c_corr = 1 written (applied 0, k_fit kept), the report says so, pipeline_reuse --identity: yes" ||
  { attrs "$tmp/flat.h5"; cat "$tmp/flat.log"; fail "no parcel effect"; }

# parcels needing more drag
mapfile -t more < <(runs more 0.05 "1:1:0.9 2:1:0.946 2:2:0.946 3:1:0.995 3:2:0.995 4:1:1.046 4:2:1.046")
"$fit" --parcel-fit "$tmp/model.h5" "${more[@]}" -o "$tmp/more.h5" >"$tmp/more.log" 2>&1 || { cat "$tmp/more.log"; fail "more: exit status"; }
"$py" -c '
import sys, h5py, math
a = h5py.File(sys.argv[1], "r")["c_corr"].attrs
assert a["applied"] == 1 and a["k"] < 0 and a["k"] == a["k_fit"] and a["k_interval"][1] < 0, dict(a)
c4 = a["a"] + (1 - a["a"]) * math.exp(-a["k"] * 3)
assert c4 > 1, c4
print("     k = %.4f [%.4f, %.4f], c_corr(4) = %.3f, p = %.3g" % (a["k"], a["k_interval"][0], a["k_interval"][1], c4, a["p_value"]))
' "$tmp/more.h5" && grep -q "^c_corr applied" "$tmp/more.log" &&
  ! "$py" "$source_dir/tools/pipeline_reuse.py" --identity "$tmp/more.h5" &&
  ok "parcels needing more drag: k < 0 fitted and applied (c_corr > 1)" || { attrs "$tmp/more.h5"; cat "$tmp/more.log"; fail "k < 0"; }

# a phi without an alpha = 1 run
mapfile -t orphan < <(runs orphan 0.1 "2:1:0.9 3:1:0.9")
"$fit" --parcel-fit "$tmp/model.h5" "${flat[@]}" "${orphan[@]}" -o "$tmp/orphan.h5" >"$tmp/orphan.log" 2>&1; s=$?
[ $s -eq 2 ] && grep -q "<phi> = 0.1 has runs with alpha = 2 but no alpha = 1 run" "$tmp/orphan.log" && ! ls "$tmp"/orphan.h5* >/dev/null 2>&1 &&
  ok "a phi without an alpha = 1 run: exit 2, nothing written ($(grep -o 'parcel fit: .*no alpha = 1 run' "$tmp/orphan.log" | head -c 90))" ||
  { cat "$tmp/orphan.log"; fail "orphan phi: exit $s"; }
[ $failures -eq 0 ] && echo "all parcel fit checks passed" || echo "$failures parcel fit check(s) failed"
exit $((failures > 0))
