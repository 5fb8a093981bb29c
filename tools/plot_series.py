#!/usr/bin/python3
"""Plot the time series of one or more runs: the vertical slip velocity, or the energies of a dry run.

    tools/plot_series.py RUN_DIR [RUN_DIR...] -o slip.png [--homogeneous 0.643] [--title TEXT]

For each run directory (or series.h5 file) it reads series.h5 and plots, against time:

  runs with a fluid   <u_slip,y>/u_ref against t/t_ref (t_ref = u_t/g from /params). The slip is the
                      series column slip_velocity (y component: <eps u>/<eps> - <phi v>/<phi>, the
                      whole-box filter of docs/models.md "Filtering"), positive when the fluid moves up
                      relative to the particles. u_ref is
                        - coupled runs (one-way, two-way): u_t of Schiller-Naumann, the convention of
                          the paper and of docs/models.md "Reference scales" (/params u_t_m_s), whatever
                          the law;
                        - quiescent runs (a fluid at rest, drag only): the single-particle terminal
                          velocity of the scene's own drag law (fluid.drag; buoyancy only with
                          fluid.pressure_gradient_force), the speed each particle relaxes to, so the curve
                          tends to 1 (dry_settling: Stokes, 0.2555 m/s, not Schiller-Naumann's 0.2185).
                      --homogeneous VALUE adds the homogeneous (unclustered) drag-law balance
                      u_slip/u_t as a dashed line (e.g. Beetstra at <phi_p> = 0.05: 0.643).
  dry runs            the kinetic, rotational and contact energies (J) against t in s (no fluid: no
                      u_t, no slip).

The mean and standard deviation over the last --window (t_ref for slip; default: the second half of
each run) are printed and, for the slip, marked on the plot. The legend names each run by its
directory (and <phi_p>); the scene, when all runs share it, is in the title.

Exit status: 0 done; 2 bad input (a missing or unreadable series, runs with and without a fluid mixed).
Uses /usr/bin/python3 with h5py, numpy and matplotlib (Agg backend: no display needed).
"""
import argparse
import math
import os
import sys

ENERGIES = (("kinetic_energy", "translational kinetic"), ("rotational_energy", "rotational kinetic"),
            ("contact_energy", "contact (spring)"))


def text(value):
    return value.decode() if isinstance(value, bytes) else str(value)


def single_particle_force_factor(law, re):
    """F(0, Re) = F_d / (3 pi mu d u) of a single particle (phi = 0) for a microscopic law (docs/models.md
    "Drag laws"; core/drag.hpp): Stokes 1; Wen-Yu (Schiller-Naumann's C_d) 1 + 0.15 Re^0.687;
    Beetstra 1 + (0.413/24)(Re + 8.4 Re^0.657) Re^0.5 / (Re^0.5 + 1)."""
    if law == "stokes":
        return 1.0
    if law == "wen-yu":
        return 1.0 + 0.15 * re ** 0.687
    if law == "beetstra":
        return 1.0 + 0.413 / 24.0 * (re + 8.4 * re ** 0.657) * re ** 0.5 / (re ** 0.5 + 1.0)
    raise ValueError(f"fluid.drag = {law!r}: no single-particle terminal velocity here (a filtered law); "
                     "expected stokes, wen-yu or beetstra")


def terminal_velocity(params):
    """Terminal velocity (m/s) of one particle of the scene under its own drag law in a fluid at rest:
    3 pi mu d F(0, Re) u = V_p (rho_p - rho_f) g, rho_f only with the pressure-gradient force (buoyancy)."""
    law = text(params["drag"])
    d, rho_p = float(params["diameter_m"]), float(params["density_kg_m3"])
    rho_f, mu = float(params["fluid_density_kg_m3"]), float(params["fluid_viscosity_Pa_s"])
    g = math.sqrt(sum(float(c) ** 2 for c in params["gravity_m_s2"]))
    buoyant = rho_f if int(params.get("pressure_gradient_force", 1)) else 0.0
    stokes = (rho_p - buoyant) * g * d * d / (18.0 * mu)
    lo, hi = 0.0, stokes  # F >= 1: the terminal velocity is at most Stokes's; bisect u = stokes / F(Re(u))
    for _ in range(200):
        u = 0.5 * (lo + hi)
        if u * single_particle_force_factor(law, rho_f * d * u / mu) > stokes:
            hi = u
        else:
            lo = u
    return 0.5 * (lo + hi)


def load(path):
    import h5py
    import numpy as np

    series = os.path.join(path, "series.h5") if os.path.isdir(path) else path
    if not os.path.exists(series):
        raise ValueError(f"{path}: no series.h5 (a run directory of cgd-generate, or a series file)")
    with h5py.File(series, "r") as f:
        if text(f.attrs.get("cgd_format", "")) != "series":
            raise ValueError(f"{series}: not a cgd series file (cgd_format = {f.attrs.get('cgd_format')!r})")
        params = dict(f["params"].attrs)
        run = dict(path=path, name=text(params.get("scene_name", os.path.basename(os.path.normpath(path)))),
                   phi=float(params.get("solids_fraction", float("nan"))),
                   directory=os.path.basename(os.path.normpath(path if os.path.isdir(path) else os.path.dirname(path)
                                                                or ".")),
                   t_s=np.asarray(f["time"][:], dtype=float), rows=len(f["time"]))
        run["fluid"] = bool(int(params.get("has_fluid", 0)))
        if not run["fluid"]:
            missing = [name for name, _ in ENERGIES if name not in f]
            if missing:
                raise ValueError(f"{series}: a dry run without the energy columns {', '.join(missing)}")
            run["energies"] = {name: np.asarray(f[name][:], dtype=float) for name, _ in ENERGIES}
            return run
        t_ref = float(params.get("t_ref_s", 0.0))
        u_t = float(params.get("u_t_m_s", 0.0))
        if not (u_t > 0 and t_ref > 0):
            raise ValueError(f"{series}: /params has no u_t_m_s/t_ref_s although the run has a fluid "
                             "(a scene without gravity?)")
        if "slip_velocity" not in f:
            raise ValueError(f"{series}: no slip_velocity column")
        slip = np.asarray(f["slip_velocity"][:], dtype=float)
        quiescent = text(params.get("coupling", "")) == "quiescent"
        if quiescent:
            u_ref, ref = terminal_velocity(params), f"u_t of {text(params['drag'])} drag"
        else:
            u_ref, ref = u_t, "u_t (Schiller-Naumann)"
    slip_y = slip[:, 1] if slip.ndim == 2 else slip
    run.update(t=run["t_s"] / t_ref, s=slip_y / u_ref, u_ref=u_ref, ref=ref, t_ref=t_ref)
    return run


def plot_slip(ax, runs, window, homogeneous, show_scene):
    import numpy as np

    for r in runs:
        t, s = r["t"], r["s"]
        label = f"{r['directory']}" + (f" ({r['name']})" if show_scene else "") + \
            f", $\\langle\\phi_p\\rangle$ = {r['phi']:.3g}"
        (line,) = ax.plot(t, s, lw=1.0, label=label)
        if len(t) > 1:
            t_end = t[-1]
            t0 = max(t_end - window, 0.0) if window else 0.5 * t_end
            sel = (t >= t0) & (t > 0)
            if sel.any():
                mean, std = float(np.mean(s[sel])), float(np.std(s[sel]))
                ax.hlines(mean, t0, t_end, colors=line.get_color(), linestyles="dotted", lw=1.5)
                print(f"{r['path']}: <u_slip,y>/u_ref over t/t_ref in [{t0:.2f}, {t_end:.2f}]: mean {mean:.4f}, "
                      f"std {std:.4f}, last {s[-1]:.4f}; max {np.max(s):.4f} (u_ref = {r['ref']} = {r['u_ref']:.4g} m/s, "
                      f"t_ref = {r['t_ref']:.4g} s, {r['rows']} rows)")
    if homogeneous is not None:
        ax.axhline(homogeneous, color="k", ls="--", lw=1.0, label=f"homogeneous drag law: {homogeneous:g}")
    refs = sorted({r["ref"] for r in runs})
    ax.set_xlabel(r"$t\,/\,t_\mathrm{ref}$  ($t_\mathrm{ref} = u_t/g$)")
    ax.set_ylabel(r"$\langle u_{\mathrm{slip},y}\rangle\,/\,u_\mathrm{ref}$" + "\n(" + "; ".join(
        f"{ref.replace('u_t', '$u_t$')} = {next(r['u_ref'] for r in runs if r['ref'] == ref):.4g} m/s"
        for ref in refs) + ")", fontsize=9)
    ax.set_ylim(bottom=0)
    return "domain-averaged slip velocity (dotted: mean over the averaging window)"


def plot_energies(ax, runs, show_scene):
    styles = ("-", "--", ":")
    for i, r in enumerate(runs):
        color = f"C{i}"
        for (name, meaning), style in zip(ENERGIES, styles):
            values = r["energies"][name]
            if not (values > 0).any():
                continue  # e.g. no rotation simulated (friction 0): nothing to draw on a log axis
            run_label = f"{r['directory']}" + (f" ({r['name']})" if show_scene else "")
            ax.plot(r["t_s"], values, color=color, ls=style, lw=1.0,
                    label=f"{run_label}: {meaning}" if len(runs) > 1 else meaning)
        print(f"{r['path']}: dry run, {r['rows']} rows; final energies "
              + ", ".join(f"{name} {r['energies'][name][-1]:.4g} J" for name, _ in ENERGIES))
    ax.set_yscale("log")
    ax.set_xlabel(r"$t$ (s)")
    ax.set_ylabel("energy of the particles (J)")
    return "energies of a dry granular run (no fluid)"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+", metavar="RUN_DIR", help="run directories (or series.h5 files)")
    ap.add_argument("-o", "--output", required=True, metavar="PNG", help="image to write")
    ap.add_argument("--homogeneous", type=float, metavar="VALUE",
                    help="homogeneous drag-law u_slip/u_t, drawn dashed (Beetstra, phi = 0.05: 0.643)")
    ap.add_argument("--window", type=float, metavar="T_REF",
                    help="average over the last T_REF units of t_ref (default: the second half of each run)")
    ap.add_argument("--title", default=None)
    a = ap.parse_args(argv)

    try:
        runs = [load(p) for p in a.runs]
        wet = {r["fluid"] for r in runs}
        if len(wet) > 1:
            raise ValueError("runs with a fluid (slip) and dry runs (energies) cannot share one plot: "
                             + ", ".join(f"{r['path']} ({'fluid' if r['fluid'] else 'dry'})" for r in runs))
    except (ValueError, OSError, KeyError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = sorted({r["name"] for r in runs})
    show_scene = len(scenes) > 1  # one scene for all: in the title, not in every legend entry
    fig, ax = plt.subplots(figsize=(7, 4.2))
    if runs[0]["fluid"]:
        title = plot_slip(ax, runs, a.window, a.homogeneous, show_scene)
    else:
        title = plot_energies(ax, runs, show_scene)
    if not show_scene:
        title = f"{scenes[0]}: {title}"
    ax.set_title(a.title or title, fontsize=10)
    ax.set_xlim(left=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    try:
        fig.savefig(a.output, dpi=120)
    except OSError as e:
        print(f"error: -o {a.output}: cannot write ({e.strerror or e})", file=sys.stderr)
        return 2
    print(f"wrote {a.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
