# Shared by the stability tests (sourced, not run by CTest): the binaries, a scratch directory, a
# small coupled scene to start from, and the checker every test applies to its run directory.
#
# Environment (set by CTest): CGD_SOURCE_DIR, CGD_BINARY_DIR; CGD_MPIEXEC (mpirun) for the 2-rank runs.
set -euo pipefail

SRC=${CGD_SOURCE_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)}
BUILD=${CGD_BINARY_DIR:-$SRC/build}
GEN=$BUILD/cgd-generate
PY=/usr/bin/python3
MPIEXEC=${CGD_MPIEXEC:-mpirun}
[ -x "$GEN" ] || { echo "FAIL: $GEN not built"; exit 1; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1

tmp=$(mktemp -d)
[ -n "${CGD_KEEP_TMP:-}" ] && echo "scratch: $tmp" || trap 'rm -rf "$tmp"' EXIT

# The paper's particles, contacts and fluid (Table 1: gamma* = 1e-3, t* = 1/50, e = 0.9, mu = 0.1,
# Beetstra drag, two-way, pressure-gradient force, Co = 0.3) in a small periodic box; each test changes
# what it is about with --set.
cat >"$tmp/base.toml" <<'EOF'
[domain]
size_dp = [16, 32, 16]
gravity = [0.0, -9.81, 0.0]
[particles]
diameter = 75e-6
density = 1500.0
solids_fraction = 0.05
velocity_rms = 0.0
seed = 3
[contact]
model = "spring-dashpot"
gamma_star = 1e-3
t_star = 0.02
restitution = 0.9
friction = 0.1
kn_over_kt = 3.5
gamman_over_gammat = 1.0
[fluid]
density = 1.3
viscosity = 1.8e-5
cells = [5, 10, 5]
courant = 0.3
coupling = "two-way"
drag = "beetstra"
pressure_gradient_force = true
[run]
end_time = 0.005
dump_interval = 0.0025
checkpoint_wall_s = 600
EOF
BASE=$tmp/base.toml

# run NAME [--np N] ARGS...: cgd-generate BASE ARGS -o $tmp/NAME (quiet); the exit status is returned,
# stdout/stderr kept in $tmp/NAME.out / .err.
run() {
  local name=$1; shift
  local np=1
  if [ "${1:-}" = "--np" ]; then np=$2; shift 2; fi
  local status=0
  if [ "$np" -gt 1 ]; then
    $MPIEXEC --allow-run-as-root --oversubscribe -np "$np" "$GEN" "$BASE" "$@" --quiet -o "$tmp/$name" \
      >"$tmp/$name.out" 2>"$tmp/$name.err" || status=$?
  else
    "$GEN" "$BASE" "$@" --quiet -o "$tmp/$name" >"$tmp/$name.out" 2>"$tmp/$name.err" || status=$?
  fi
  return $status
}

# run_ok NAME ARGS...: run, which must exit 0.
run_ok() {
  local name=$1 status=0
  local t0=$SECONDS
  run "$@" || status=$?
  if [ $status -ne 0 ]; then
    echo "FAIL $name: cgd-generate exit status $status"; sed 's/^/   /' "$tmp/$name.err" | tail -5; exit 1
  fi
  echo "ran $name in $((SECONDS - t0)) s: $(grep -m1 'particle count' "$tmp/$name.out" | sed 's/  */ /g')"
}

# check RUN_DIR [--expect-floored] [--stored-energy] [--np N]: the checks every stability test makes (see check.py below).
cat >"$tmp/check.py" <<'PYEOF'
"""Checks of a completed coupled run (tests/stability): prints the figures, exits 1 on a failure.

* the run completed (DONE) its fixed number of steps: the last series row is step round(end_time/dt_DEM)
  (k round(dump_interval/dt_DEM) when end_time is k dump intervals, sim/run.cpp coupled_end_step);
* no NaN/Inf in any series column or in any snapshot array (particles, fluid);
* bounded kinetic energy. The only energy source of the periodic sedimenting box is the driving
  (gravity less the removed mean pressure gradient rho_mix g). With zero total momentum its power is
  P = (rho_p - rho_f) phi (1 - phi) V |g| u_slip (the buoyant weight times the slip along -g; docs/models.md
  driving and slip), and drag, contacts and viscosity only dissipate. So
      E(t) = KE_p + KE_rot + KE_fluid  <=  E(0) + int_0^t P dt'
  (contact spring energy >= 0 is left out of E: that only makes the bound looser). Tolerance 5 % of
  the right-hand side for the discrete scheme. As u_slip could itself run away, independent caps:
  |u_slip,y| <= 5 u_t (clustered suspensions reach ~1-2 u_t, the homogeneous Beetstra value is < 1)
  and the rms particle speed <= velocity_rms + 5 u_t;
* void fraction of every snapshot within [floor, 1] (floor 0.3, coupler.hpp), its mean equal to
  1 - <phi_p> to 1e-9 (the floor is conservative), pressure and fluid velocity finite;
* the fluid's continuity residual (relative) <= 1e-6 on every row;
* particle overlaps measured from the snapshot positions below the engine's blow-up limit (25 % of d);
* with --expect-floored: floored_cells > 0 on some row and cells at the floor in some snapshot;
* with --stored-energy: the run starts with energy the bound above does not count (a particle-phase pressure's
  sum_c V_c psi(phi_c), core/particle_stress.hpp, in a packing past close packing), so the energy bound is not
  checked; the caps on the slip and the rms speed, and every other check, are.
"""
import glob, math, os, sys
import h5py
import numpy as np

def main():
    args = sys.argv[1:]
    run = args[0]
    expect_floored = "--expect-floored" in args
    stored_energy = "--stored-energy" in args
    fails = []
    def need(ok, what):
        if not ok:
            fails.append(what)
    need(os.path.exists(os.path.join(run, "DONE")), "no DONE marker: the run did not complete")
    s = h5py.File(os.path.join(run, "series.h5"), "r")
    p = s["params"].attrs
    floor = float(p["void_fraction_floor"]) if "void_fraction_floor" in p else 0.3  # [numerics]
    for k in s.keys():
        if isinstance(s[k], h5py.Dataset):
            need(np.all(np.isfinite(s[k][:])), f"series column {k} has non-finite values")
    step = s["step"][:]
    t = s["time"][:]
    steps = int(round(p["end_time_s"] / p["dt_dem_s"]))
    # a coupled run whose end is a whole number k of snapshot intervals ends on the k-th snapshot step
    # (sim/run.cpp coupled_end_step)
    if p["dump_interval_s"] > 0:
        k = round(p["end_time_s"] / p["dump_interval_s"])
        if k >= 1 and abs(p["end_time_s"] / p["dump_interval_s"] - k) < 1e-6 * k:
            steps = int(k) * max(1, int(round(p["dump_interval_s"] / p["dt_dem_s"])))
    need(int(step[-1]) == steps, f"last series row at step {int(step[-1])}, expected {steps}")
    u_t = float(p["u_t_m_s"])
    V = float(np.prod(p["box_size_m"]))
    g = np.asarray(p["gravity_m_s2"], float)
    gn = float(np.linalg.norm(g))
    down = g / gn if gn > 0 else np.array([0.0, -1.0, 0.0])
    rho_p, rho_f = float(p["density_kg_m3"]), float(p["fluid_density_kg_m3"])
    phi = s["solids_fraction"][:]
    slip = s["slip_velocity"][:]
    slip_up = -(slip @ down)  # along -g
    P = (rho_p - rho_f) * phi * (1 - phi) * V * gn * slip_up
    E_in = np.concatenate([[0.0], np.cumsum(0.5 * (P[1:] + P[:-1]) * np.diff(t))])
    E = s["kinetic_energy"][:] + s["rotational_energy"][:] + s["fluid_kinetic_energy"][:]
    M = float(p["particle_count"]) * float(p["parcel_mass_kg"])
    bound = 1.05 * (E[0] + np.maximum(E_in, 0.0)) + 1e-9 * 0.5 * M * u_t**2
    worst = int(np.argmax(E / bound))
    need(stored_energy or np.all(E <= bound), f"energy above the bound at t = {t[worst]:.4g} s: E = {E[worst]:.4g} J > {bound[worst]:.4g} J")
    need(np.all(np.abs(slip[:, 1]) <= 5 * u_t), f"|u_slip,y| above 5 u_t: max {np.abs(slip[:, 1]).max() / u_t:.3g} u_t")
    v_rms = np.sqrt(2 * s["kinetic_energy"][:] / M)
    v0 = float(p["velocity_rms_m_s"])
    need(np.all(v_rms <= v0 + 5 * u_t), f"rms particle speed {v_rms.max():.3g} m/s above velocity_rms + 5 u_t")
    cont = s["continuity_residual_rel"][:]
    need(cont.max() <= 1e-6, f"continuity residual {cont.max():.3g} > 1e-6")
    floored = s["floored_cells"][:]
    snaps = sorted(glob.glob(os.path.join(run, "snapshots", "snap_*.h5")))
    need(len(snaps) >= 2, f"{len(snaps)} snapshots, expected at least 2")
    eps_min, eps_max, at_floor, max_overlap, p_span, u_max = 1.0, 0.0, 0, 0.0, 0.0, 0.0
    L = np.asarray(p["box_size_m"], float)
    d = float(p["parcel_diameter_m"])
    for f in snaps:
        with h5py.File(f, "r") as h:
            x = h["particles/position"][:]
            for key in h["particles"].keys():
                need(np.all(np.isfinite(h["particles/" + key][:])), f"{os.path.basename(f)}: particles/{key} not finite")
            need(np.all((x >= 0) & (x <= L)), f"{os.path.basename(f)}: positions outside the box")
            eps = h["fluid/void_fraction"][:]
            pr = h["fluid/pressure"][:]
            u = h["fluid/velocity"][:]
            need(np.all(np.isfinite(eps)) and np.all(np.isfinite(pr)) and np.all(np.isfinite(u)),
                 f"{os.path.basename(f)}: fluid fields not finite")
            need(eps.min() >= floor - 1e-12 and eps.max() <= 1 + 1e-12,
                 f"{os.path.basename(f)}: void fraction in [{eps.min():.6g}, {eps.max():.6g}], outside [{floor}, 1]")
            # parcels: alpha^3 primaries each
            phi_mean = float(h["params"].attrs["particle_count"]) * float(h["params"].attrs["particle_volume_m3"]) * float(h["params"].attrs["parcel_size"]) ** 3 / V
            need(abs(eps.mean() - (1 - phi_mean)) < 1e-9, f"{os.path.basename(f)}: mean void fraction {eps.mean():.12g} != 1 - <phi> = {1 - phi_mean:.12g}")
            eps_min, eps_max = min(eps_min, eps.min()), max(eps_max, eps.max())
            at_floor += int(np.sum(eps <= floor + 1e-12))
            p_span = max(p_span, float(pr.max() - pr.min()))
            u_max = max(u_max, float(np.abs(u).max()))
            try:
                from scipy.spatial import cKDTree
                tree = cKDTree(np.mod(x, L), boxsize=L)
                pairs = tree.query_pairs(d, output_type="ndarray")
                if len(pairs):
                    dx = x[pairs[:, 0]] - x[pairs[:, 1]]
                    dx -= L * np.round(dx / L)
                    max_overlap = max(max_overlap, float((d - np.linalg.norm(dx, axis=1)).max() / d))
            except ImportError:
                pass
    need(max_overlap < 0.25, f"particle overlap {max_overlap:.3g} d in a snapshot, at or above the 25 % blow-up limit")
    if expect_floored:
        need(floored.max() > 0, "floored_cells stayed 0: the void-fraction floor was never reached")
        need(at_floor > 0, "no snapshot has a cell at the void-fraction floor")
    print(f"  {os.path.basename(run)}: {steps} steps, {len(t) - 1} fluid steps (dt_fluid {s['dt_fluid'][1:].min():.3g}..{s['dt_fluid'][1:].max():.3g} s), "
          f"{int(p['particle_count'])} particles; E_max/bound {np.max(E / bound):.3g}; "
          f"slip_y/u_t {slip[-1, 1] / u_t:.3f} (max {np.abs(slip[:, 1]).max() / u_t:.3f}); rms speed max {v_rms.max():.3g} m/s; "
          f"eps in [{eps_min:.4f}, {eps_max:.4f}]; max phi {s['max_solids_fraction'][:].max():.4f}; "
          f"floored cells max {int(floored.max())} ({int(np.sum(floored > 0))} rows); continuity {cont.max():.2g}; "
          f"pressure span {p_span:.3g} Pa; max |u_f| {u_max:.3g} m/s; max overlap (snapshots) {max_overlap:.3g} d; "
          f"PCG iterations max {int(s['pressure_iterations'][:].max())}")
    if fails:
        for f in fails:
            print(f"FAIL {os.path.basename(run)}: {f}")
        return 1
    return 0

sys.exit(main())
PYEOF

check() { "$PY" "$tmp/check.py" "$tmp/$1" "${@:2}"; }
