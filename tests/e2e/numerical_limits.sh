#!/usr/bin/env bash
# Numerical limits stated (issue 10, item 6):
#  * the largest overlap passing numerics.overlap_warning_fraction of numerics.overlap_limit is warned about
#    once, on stderr and in series.h5's `warnings` attribute, with the contact stiffness (or gamma*) that
#    would keep that impact below (the peak overlap of an impact scales as k_n^(-1/2));
#  * the constants that change results are scene keys ([numerics]) written to every file's /params;
#    nonsense values are refused with exit 2.
# (The Courant limit of the fluid scheme is checked in tests/unit/test_scene.cpp.)
set -euo pipefail
BIN=${CGD_BINARY_DIR:?}/cgd-generate
SCENE=${CGD_SOURCE_DIR:?}/data/scenes/granular_gas.toml
PY=/usr/bin/python3
tmp=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$tmp"' EXIT

# granular gas (6,258 particles, 0.1 m/s rms, k_n 1.27 N/m): the first impacts reach ~2.5 % of d within
# 20 steps; warn at 0.1 x 25 % = 2.5 %. 400 steps.
common=(--quiet --set run.end_time=2.872e-4 --set run.dump_interval=1.436e-4 --set numerics.overlap_warning_fraction=0.1
        --set numerics.sort_interval_steps=500 --set numerics.void_fraction_floor=0.25)
timeout 120 "$BIN" "$SCENE" "${common[@]}" -o "$tmp/a" > "$tmp/a.out" 2> "$tmp/a.err"
n=$(grep -c "^warning at step" "$tmp/a.err" || true)
[ "$n" -eq 1 ] || { echo "FAIL: $n overlap warnings on stderr, expected 1"; cat "$tmp/a.err"; exit 1; }
k=$(sed -n 's/.*contact.stiffness = \([0-9.e+-]*\) N\/m.*/\1/p' "$tmp/a.err")
[ -n "$k" ] || { echo "FAIL: the warning names no stiffness: $(cat "$tmp/a.err")"; exit 1; }
echo "warning: $(cut -c1-400 "$tmp/a.err")"

"$PY" - "$tmp/a" "$tmp/b" <<'PYEOF'
import glob, re, sys, h5py, numpy as np
a, b = sys.argv[1], sys.argv[2]
with h5py.File(a + "/series.h5") as s:
    w = [x.decode() if isinstance(x, bytes) else x for x in s.attrs["warnings"]]
    assert len(w) == 1 and "overlap" in w[0], f"series warnings: {w}"
    t_warn = float(re.search(r"\(t = ([0-9.e+-]+) s\)", w[0]).group(1))
# every file's /params holds the numerics (the --set values and the defaults)
want = {"void_fraction_floor": 0.25, "overlap_limit": 0.25, "overlap_warning_fraction": 0.1,
        "viscous_safety": 0.8, "drag_safety": 0.5, "sort_interval_steps": 500}
files = [a + "/series.h5", a + "/checkpoint.h5"] + sorted(glob.glob(a + "/snapshots/snap_*.h5"))
for f in files:
    with h5py.File(f) as h:
        for key, value in want.items():
            assert key in h["params"].attrs, f"{f}: /params lacks {key}"
            assert h["params"].attrs[key] == value, f"{f}: /params {key} = {h['params'].attrs[key]}, expected {value}"
# the stiffness it names: the peak overlap of an impact at speed v is v sqrt(m_eff/k_n) (linear spring-
# dashpot), so k_n x (overlap / (0.8 threshold))^2 brings this impact to 0.8 of the threshold (tolerance: the
# message's 3 digits)
m = re.search(r"reached ([0-9.e+-]+) % of the diameter.*contact.stiffness = ([0-9.e+-]+) N/m \(now ([0-9.e+-]+)\)", w[0])
overlap, k_new, k_now = float(m.group(1)) / 100, float(m.group(2)), float(m.group(3))
expected = k_now * (overlap / (0.8 * 0.025)) ** 2
assert abs(k_new / expected - 1) < 1e-2, f"suggested stiffness {k_new}, expected {expected}"
print(f"one warning at t = {t_warn:.3g} s (overlap {overlap:.4f} d, suggested k_n {k_new} N/m); "
      f"/params numerics in {len(files)} files")
PYEOF

# nonsense numerics are refused, nothing written
for bad in numerics.void_fraction_floor=1.5 numerics.overlap_limit=0 numerics.sort_interval_steps=0 numerics.drag_safety=2; do
  status=0
  timeout 60 "$BIN" "$SCENE" --quiet --set "$bad" -o "$tmp/bad" > /dev/null 2> "$tmp/bad.err" || status=$?
  key=${bad%%=*}
  if [ $status -ne 2 ] || ! grep -qF "$key" "$tmp/bad.err" || [ -e "$tmp/bad" ]; then
    echo "FAIL: --set $bad: status $status"; cat "$tmp/bad.err"; exit 1
  fi
done
echo "numerical limits: passed"
