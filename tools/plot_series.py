#!/usr/bin/python3
"""Plot the domain-averaged vertical slip velocity of one or more runs against time.

    tools/plot_series.py RUN_DIR [RUN_DIR...] -o slip.png [--homogeneous 0.643] [--title TEXT]

For each run directory (or series.h5 file) it reads series.h5 and plots <u_slip,y>/u_t against
t/t_ref, with u_t and t_ref from the file's /params attributes (u_t_m_s, t_ref_s; models.md
conventions). The slip is the series column slip_velocity (y component; models.md: <eps u>/<eps> -
<phi v>/<phi>), positive when the fluid moves up relative to the particles. --homogeneous VALUE adds
the homogeneous (unclustered) drag-law balance u_slip/u_t as a dashed line (e.g. Beetstra at
<phi_p> = 0.05: 0.643, models.md). The mean and standard deviation over the last --window t_ref
(default: the second half of each run) are printed and marked on the plot.

Exit status: 0 done; 2 bad input (a missing or unreadable series, a file without u_t).
Uses /usr/bin/python3 with h5py, numpy and matplotlib (Agg backend: no display needed).
"""
import argparse
import os
import sys


def load(path):
    import h5py
    import numpy as np

    series = os.path.join(path, "series.h5") if os.path.isdir(path) else path
    if not os.path.exists(series):
        raise ValueError(f"{path}: no series.h5 (a run directory of cgd-generate, or a series file)")
    with h5py.File(series, "r") as f:
        if f.attrs.get("cgd_format", b"") not in ("series", b"series"):
            raise ValueError(f"{series}: not a cgd series file (cgd_format = {f.attrs.get('cgd_format')!r})")
        params = f["params"].attrs
        u_t = float(params.get("u_t_m_s", 0.0))
        t_ref = float(params.get("t_ref_s", 0.0))
        if not (u_t > 0 and t_ref > 0):
            raise ValueError(f"{series}: /params has no u_t_m_s/t_ref_s (a run without a fluid?)")
        if "slip_velocity" not in f:
            raise ValueError(f"{series}: no slip_velocity column")
        t = np.asarray(f["time"][:], dtype=float)
        slip = np.asarray(f["slip_velocity"][:], dtype=float)
        name = params.get("scene_name", os.path.basename(os.path.normpath(path)))
        if isinstance(name, bytes):
            name = name.decode()
        phi = float(params.get("solids_fraction", float("nan")))
    slip_y = slip[:, 1] if slip.ndim == 2 else slip
    return dict(path=path, name=str(name), phi=phi, t=t / t_ref, s=slip_y / u_t, u_t=u_t, t_ref=t_ref)


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
    except (ValueError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fig, ax = plt.subplots(figsize=(7, 4.2))
    for r in runs:
        t, s = r["t"], r["s"]
        # the run directory tells runs of one scene apart (e.g. the same scene with other --set values)
        label = f"{os.path.basename(os.path.normpath(r['path']))}: {r['name']} ($\\langle\\phi_p\\rangle$ = {r['phi']:.3g})"
        (line,) = ax.plot(t, s, lw=1.0, label=label)
        if len(t) > 1:
            t_end = t[-1]
            t0 = max(t_end - a.window, 0.0) if a.window else 0.5 * t_end
            sel = (t >= t0) & (t > 0)
            if sel.any():
                mean, std = float(np.mean(s[sel])), float(np.std(s[sel]))
                ax.hlines(mean, t0, t_end, colors=line.get_color(), linestyles="dotted", lw=1.5)
                print(f"{r['path']}: <u_slip,y>/u_t over t/t_ref in [{t0:.2f}, {t_end:.2f}]: mean {mean:.4f}, "
                      f"std {std:.4f}, last {s[-1]:.4f}; max {np.max(s):.4f} (u_t = {r['u_t']:.4g} m/s, "
                      f"t_ref = {r['t_ref']:.4g} s, {len(t)} rows)")
    if a.homogeneous is not None:
        ax.axhline(a.homogeneous, color="k", ls="--", lw=1.0, label=f"homogeneous drag law: {a.homogeneous:g}")
    ax.set_xlabel(r"$t\,/\,t_\mathrm{ref}$  ($t_\mathrm{ref} = u_t/g$)")
    ax.set_ylabel(r"$\langle u_{\mathrm{slip},y}\rangle\,/\,u_t$")
    ax.set_title(a.title or "domain-averaged slip velocity (dotted: mean over the averaging window)", fontsize=10)
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(a.output, dpi=120)
    print(f"wrote {a.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
