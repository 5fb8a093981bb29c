#!/usr/bin/python3
"""How a resolved run went, window by window of simulated time: the stability and cost figures of a run's
series file (RUN_DIR/series.h5, one row per fluid step; docs/schema-run.md), for the hard cases the project
must keep stable (dense suspensions, stiff contacts) and for the real cost of a box.

One row per window of WINDOW t_ref (default 5) with
  * slip      the mean of <u_slip,y>/u_t over the window's rows (the domain slip, no error bar: the study's
              batch means give that, tools/study.py);
  * overlap   the largest max_overlap_rel (largest overlap / d_p) of the window;
  * contacts  the mean contacts per particle;
  * steps/rebuild  DEM steps per neighbour-list rebuild (from the cumulative counters);
  * dt_fluid  the mean fluid step (s), and the mean and largest PCG iterations of the pressure solve;
  * max phi   the largest cell solids fraction; floored  the most cells at the void-fraction floor;
  * wall s/t_ref  wall seconds per t_ref, and wall ns per particle-step (x RANKS when given: the run's rank
              count, which the series does not record). A run that shared the machine is slower than an
              idle one; the step counts are not.
With --timers, a second table: where each window's wall time went, in % of it, from the series' timers (rank 0's
cumulative seconds per phase, docs/schema-run.md): neighbour lists (time_neighbor_s), forces and integration
(time_force_integrate_s), drag coupling (time_coupling_s), the fluid (predictor, pressure, correction), communication
(time_comm_s), output (output, checkpoint, diagnostics), and what no timer holds (other).

usage: /usr/bin/python3 tools/run_health.py RUN_DIR_OR_SERIES [--window 5] [--ranks 1] [--markdown] [--timers]
Exit status 0; 2 for a file that is not a readable series (the message names the file and what is missing), or with
--timers a series without the timers (written before them).
(Debian's h5py/numpy belong to /usr/bin/python3.)"""
import argparse
import math
import os
import signal
import sys

import h5py
import numpy as np

COLUMNS = ["time", "step", "wall_seconds", "neighbor_rebuilds", "contacts_per_particle", "max_overlap_rel",
           "dt_fluid", "pressure_iterations", "slip_velocity", "max_solids_fraction", "floored_cells"]
# --timers: the share of the wall time per phase (label, the series' cumulative timers it sums)
TIMERS = [("neighbour", ["time_neighbor_s"]), ("forces+integrate", ["time_force_integrate_s"]),
          ("coupling", ["time_coupling_s"]),
          ("fluid", ["time_fluid_predictor_s", "time_fluid_pressure_s", "time_fluid_correction_s"]),
          ("comm", ["time_comm_s"]), ("output", ["time_output_s", "time_checkpoint_s", "time_diagnostics_s"])]


def fail(msg):
    print(f"run_health.py: {msg}", file=sys.stderr)
    sys.exit(2)


def read_series(path, timers=False):
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        fail(f"{path}: not a readable HDF5 file ({e})")
    with f:
        columns = COLUMNS + ([c for _, cs in TIMERS for c in cs] if timers else [])
        missing = [c for c in columns if c not in f]
        if missing:
            fail(f"{path}: not a run's series: dataset(s) {', '.join('/' + m for m in missing)} missing")
        if "params" not in f:
            fail(f"{path}: not a run's series: group /params missing")
        p = f["params"].attrs
        for key in ("t_ref_s", "u_t_m_s", "particle_count"):
            if key not in p:
                fail(f"{path}: /params attribute {key} missing")
        data = {c: np.asarray(f[c][:], dtype=float) for c in columns}
        n = len(data["time"])
        for c in columns:
            if data[c].shape[0] != n:
                fail(f"{path}: /{c} has {data[c].shape[0]} rows, /time has {n}")
        if data["slip_velocity"].ndim != 2 or data["slip_velocity"].shape[1] != 3:
            fail(f"{path}: /slip_velocity has shape {data['slip_velocity'].shape}, expected ({n}, 3)")
        return data, float(p["t_ref_s"]), float(p["u_t_m_s"]), float(p["particle_count"])


def windows(data, t_ref, u_t, n_particles, window, ranks):
    """One dict per window (k w, (k+1) w] t_ref: a row reports the fluid step that ends at its time, so the
    means are over the rows in the window and the counters (steps, rebuilds, wall clock) are differenced
    from the last row at or before the window's start to the window's last row."""
    t = data["time"] / t_ref
    rows = []
    if len(t) < 2:
        return rows
    eps = 1e-9 * window  # times are multiples of dt_fluid / t_ref: an edge row must not fall out by round-off
    edges = window * np.arange(max(1, math.ceil((t[-1] - eps) / window)) + 1)
    # a last stretch shorter than half a window (a run ends a fluid step past its end time) joins the window
    # before it
    if len(edges) > 2 and t[-1] - edges[-2] < 0.5 * window:
        edges = np.delete(edges, -2)
    for a, b in zip(edges[:-1], edges[1:]):
        sel = np.nonzero((t > a + eps) & (t <= b + eps))[0]
        before = np.nonzero(t <= a + eps)[0]
        if len(sel) < 1 or len(before) < 1:
            continue
        i0, i1 = before[-1], sel[-1]
        steps = data["step"][i1] - data["step"][i0]
        rebuilds = data["neighbor_rebuilds"][i1] - data["neighbor_rebuilds"][i0]
        wall = data["wall_seconds"][i1] - data["wall_seconds"][i0]
        dt_tref = t[i1] - t[i0]
        it = data["pressure_iterations"][sel]
        rows.append({
            "from": a, "to": min(b, t[-1]),
            "slip": float(np.mean(data["slip_velocity"][sel, 1])) / u_t,
            "overlap": float(np.max(data["max_overlap_rel"][sel])),
            "contacts": float(np.mean(data["contacts_per_particle"][sel])),
            "steps_per_rebuild": steps / rebuilds if rebuilds > 0 else math.inf,
            "dt_fluid": float(np.mean(data["dt_fluid"][sel])),
            "pcg_mean": float(np.mean(it)), "pcg_max": float(np.max(it)),
            "max_phi": float(np.max(data["max_solids_fraction"][sel])),
            "floored": float(np.max(data["floored_cells"][sel])),
            # a restart's first row may repeat the checkpoint's wall clock: a window whose wall span is not
            # positive reports no rate
            "wall_per_tref": wall / dt_tref if wall > 0 and dt_tref > 0 else math.nan,
            "ns_per_ps": 1e9 * wall * ranks / (n_particles * steps) if wall > 0 and steps > 0 else math.nan,
        })
        if "time_neighbor_s" in data:  # --timers: % of the window's wall time per phase, the rest "other"
            shares = {label: 100.0 * sum(data[c][i1] - data[c][i0] for c in cs) / wall if wall > 0 else math.nan
                      for label, cs in TIMERS}
            shares["other"] = 100.0 - sum(shares.values())
            rows[-1]["timers"] = shares
    return rows


HEAD = ["t/t_ref", "slip/u_t", "max overlap/d", "contacts/particle", "steps/rebuild", "dt_fluid s",
        "PCG it mean/max", "max phi", "floored", "wall s/t_ref", "wall ns/ps"]


TIMER_HEAD = ["t/t_ref"] + [label + " %" for label, _ in TIMERS] + ["other %"]


def timer_cells(r):
    return [f"{r['from']:.0f}-{r['to']:.1f}"] + [f"{r['timers'][label]:.1f}" for label, _ in TIMERS] + \
        [f"{r['timers']['other']:.1f}"]


def print_table(head, table, markdown):
    if markdown:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
        for c in table:
            print("| " + " | ".join(c) + " |")
    else:
        w = [max(len(h), *(len(c[k]) for c in table)) if table else len(h) for k, h in enumerate(head)]
        print("  ".join(h.rjust(w[k]) for k, h in enumerate(head)))
        for c in table:
            print("  ".join(x.rjust(w[k]) for k, x in enumerate(c)))


def cells(r):
    return [f"{r['from']:.0f}-{r['to']:.1f}", f"{r['slip']:.3f}", f"{r['overlap']:.3f}", f"{r['contacts']:.3f}",
            f"{r['steps_per_rebuild']:.1f}", f"{r['dt_fluid']:.3g}", f"{r['pcg_mean']:.1f}/{r['pcg_max']:.0f}",
            f"{r['max_phi']:.3f}", f"{r['floored']:.0f}", f"{r['wall_per_tref']:.0f}", f"{r['ns_per_ps']:.1f}"]


def main():
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # `| head` closes the pipe: no traceback
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run", help="a run directory (holding series.h5) or a series file")
    ap.add_argument("--window", type=float, default=5.0, help="t_ref per row (default 5)")
    ap.add_argument("--ranks", type=int, default=1, help="the run's rank count, for ns per particle-step")
    ap.add_argument("--markdown", action="store_true", help="a Markdown table instead of text")
    ap.add_argument("--timers", action="store_true", help="also the share of the wall time per phase")
    a = ap.parse_args()
    if not a.window > 0:
        fail(f"--window {a.window}: must be > 0 t_ref")
    if a.ranks < 1:
        fail(f"--ranks {a.ranks}: must be >= 1")
    path = os.path.join(a.run, "series.h5") if os.path.isdir(a.run) else a.run
    if not os.path.exists(path):
        fail(f"{path}: no such file")
    data, t_ref, u_t, n = read_series(path, a.timers)
    rows = windows(data, t_ref, u_t, n, a.window, a.ranks)
    print(f"{path}: {n:.0f} particles, {data['time'][-1] / t_ref:.2f} t_ref, {int(data['step'][-1])} DEM steps")
    print_table(HEAD, [cells(r) for r in rows], a.markdown)
    if a.timers:
        print()
        print_table(TIMER_HEAD, [timer_cells(r) for r in rows], a.markdown)


if __name__ == "__main__":
    main()
