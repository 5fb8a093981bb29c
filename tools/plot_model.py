#!/usr/bin/python3
"""Plot a drag model file of cgd-fit (docs/schema-drag-model.md).

Left: h(phi) with its 95 % band and the per-bin estimates (the paper's Figure 1); middle: H(F, phi) against phi
at the smallest, a middle and the largest calibrated F, beside Radl 2014's at the same F (the fitted a multiplies
F^n and Radl's a multiplies F: the a's are not comparable, H is); right: H(F, phi) = h/(1 + aF^n) against F (n = the file's width_exponent, 1 = the paper's) for a few phi, with bands at the data's widths.
Radl & Sundaresan 2014 (the published piecewise cubics, data/reference/radl2014-filtered-drag.csv) is
drawn beside the fit, dashed. The left and middle panels run to --phi-to (default 0.6, a fluidized bed's emulsion):
beyond the model's phi_max (its largest fitted bin) the model holds its end values (docs/schema-drag-model.md), drawn
dotted over a grey band that says where the data end.

    /usr/bin/python3 tools/plot_model.py out/fit/model.h5 -o out/fit/model.png
"""
import argparse
import os

import h5py

import cgd_schema  # tools/cgd_schema.py: the spellings shared with core/schema/
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def de_boor(t, c, k, x):
    n = len(c)
    x = min(max(x, t[k - 1]), t[n])
    i = min(max(int(np.searchsorted(t[:n], x, side="right")) - 1, k - 1), n - 1)
    d = [c[j + i - k + 1] for j in range(k)]
    for r in range(1, k):
        for j in range(k - 1, r - 1, -1):
            left, right = t[j + i - k + 1], t[j + 1 + i - r]
            alpha = (x - left) / (right - left) if right > left else 0.0
            d[j] = (1 - alpha) * d[j - 1] + alpha * d[j]
    return d[k - 1]


def radl2014():
    """h(phi), a(phi) of the published model from the reference csv."""
    here = os.path.dirname(os.path.abspath(__file__))
    rows = {"a": [], "h": []}
    with open(os.path.join(here, "..", "data", "reference", "radl2014-filtered-drag.csv")) as f:
        for line in f:
            if line.startswith("#") or line.startswith("function") or not line.strip():
                continue
            fn, *v = line.strip().split(",")
            rows[fn].append([float(x) for x in v])

    def curve(fn):
        def value(phi):
            for lo, hi, p0, c0, c1, c2, c3 in rows[fn]:
                if lo <= phi < hi:
                    x = phi - p0
                    return c0 + c1 * x + c2 * x * x + c3 * x ** 3
            return rows[fn][-1][3]
        return np.vectorize(value)

    return curve("h"), curve("a")


def beyond_grid(phi_end, phi_to, n=30):
    """The phi where a plot to phi_to runs past the model's data (phi_end = phi_max): n points from phi_end to
    phi_to, none when phi_to <= phi_end."""
    return np.linspace(phi_end, phi_to, n) if phi_to > phi_end else np.array([])


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("model")
    p.add_argument("-o", "--output", default=None, help="image file (default: MODEL with .png)")
    p.add_argument("--phi-to", type=float, default=0.6,
                   help="right end of the phi axes (default 0.6; at least the model's phi_max): beyond phi_max the held ends")
    args = p.parse_args()
    if not 0 < args.phi_to <= 0.65:
        p.error(f"--phi-to {args.phi_to}: allowed 0 < phi <= 0.65 (random close packing 0.64)")
    out = args.output or os.path.splitext(args.model)[0] + ".png"
    with h5py.File(args.model, "r") as f:
        b = {k: f["bands"][k][()] for k in f["bands"]}
        data = {k: f["data"][k][()] for k in f["data"]} if "data" in f else None
        bins = {k: f["bins"][k][()] for k in f["bins"]}
        th, ch, kh = f["h/knots"][()], f["h/coefficients"][()], int(f["h"].attrs["order"])
        phi_crit, h_max = float(f.attrs["phi_crit"]), float(f.attrs["h_max"])
        base = cgd_schema.micro_law(f.attrs)
        cv = f["diagnostics"].attrs["cv_rms_H"]
        n = float(f.attrs.get("width_exponent", 1.0))  # absent in files older than the attribute: 1
    rh, ra = radl2014()
    phi = b["phi"]
    # beyond the data: the model holds h, a (and so H and the bands) at their values at phi_max
    phi_end = float(phi[-1])
    beyond = beyond_grid(phi_end, args.phi_to)
    phi_all = np.concatenate([phi, beyond])

    def held(axis, v, low, high, color, alpha):
        """The held ends past phi_max: v[-1] dotted over the band low[-1]..high[-1]."""
        if len(beyond):
            axis.fill_between(beyond, low[-1], high[-1], color=color, alpha=alpha)
            axis.plot(beyond, np.full(len(beyond), v[-1]), ":", color=color)

    def shade(axis):
        if len(beyond):
            axis.axvspan(phi_end, args.phi_to, color="grey", alpha=0.12, lw=0)
            axis.text(0.5 * (phi_end + args.phi_to), 0.97, f"no data\n(> {phi_end:.3f}):\nends held", ha="center",
                      va="top", fontsize=7, color="dimgrey", transform=axis.get_xaxis_transform())
    bound = bins["used"] == 1
    if "at_bound" in bins:
        bound &= bins["at_bound"] == 1
    else:
        bound &= False
    used = (bins["used"] == 1) & ~bound  # bins at a bound: open symbols, no error bars
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.5))
    ax[0].fill_between(phi, b["h_low"], b["h_high"], alpha=0.3, label="95 % band")
    line, = ax[0].plot(phi, b["h"], label="fit (P-spline)")
    held(ax[0], b["h"], b["h_low"], b["h_high"], line.get_color(), 0.12)
    # per-bin errors: the bootstrap's (widths' correlation included) when the file has them
    se_h = bins.get("h_stderr_bootstrap", bins["h_stderr"])
    se_log_a = bins.get("log_a_stderr_bootstrap", bins["log_a_stderr"])
    ax[0].errorbar(bins["phi"][used], bins["h"][used], yerr=1.96 * se_h[used], fmt="o", ms=3,
                   label="per-bin fit")
    if bound.any():
        ax[0].plot(bins["phi"][bound], bins["h"][bound], "o", mfc="none", ms=5, label="per-bin fit at a bound")
    ax[0].plot(phi_all, rh(phi_all), "k--", label="Radl & Sundaresan 2014")
    ax[0].set_ylim(-0.2, 1.05)
    shade(ax[0])
    ax[0].axvline(phi_crit, color="grey", lw=0.5)
    ax[0].set(xlabel=r"$\bar\phi_p$", ylabel="h", title="h: largest drag correction (F -> 0)")
    ax[0].legend(fontsize=8)
    # H(F, phi) against phi at a few of the calibrated F: the fit (h/(1 + aF^n), its 95 % band) beside Radl 2014's
    # h/(1 + aF) at the same F. The a's themselves are not comparable when n != 1 (a multiplies F^n, Radl's a F)
    Fs = np.unique(b["F"])
    picks = sorted({0, len(Fs) // 2, len(Fs) - 1}) if len(Fs) else []
    for k in picks:
        Fk = Fs[k]
        row = int(np.argmin(abs(b["F"] - Fk)))
        H = b["h"] / (1 + b["a"] * Fk**n)
        line, = ax[1].plot(phi, H, label=f"fit, F = {Fk:.3g}")
        ax[1].fill_between(phi, b["H_low"][row], b["H_high"][row], color=line.get_color(), alpha=0.2)
        held(ax[1], H, b["H_low"][row], b["H_high"][row], line.get_color(), 0.1)
        ax[1].plot(phi_all, rh(phi_all) / (1 + ra(phi_all) * Fk), "--", color=line.get_color(), lw=1,
                   label=f"Radl 2014, F = {Fk:.3g}")
    ax[1].axhline(0, color="k", lw=0.5)
    ax[1].set(xlabel=r"$\bar\phi_p$", ylabel=r"H = h/(1 + a F$^n$)",
              title="H(F, φ) at the calibrated F: fit (band 95 %) vs Radl 2014 (dashed)")
    ax[1].set_ylim(-0.1, 1.05)
    shade(ax[1])
    ax[1].legend(fontsize=7)
    F = np.geomspace(max(b["F"].min() / 3, 1e-3), b["F"].max() * 3, 100)
    for target in (0.05, 0.1, 0.2, 0.3, 0.4):
        if target > phi[-1]:
            continue
        if data is not None:  # the bin nearest to the target, its data at every width
            j = int(np.nanargmin(abs(data["phi"] - target)))
            if not np.any(np.isfinite(data["H"][:, j])):
                continue
            p_j = data["phi"][j]
        else:
            p_j = target
        i = int(np.argmin(abs(phi - p_j)))
        line, = ax[2].plot(F, b["h"][i] / (1 + b["a"][i] * F**n), label=rf"$\bar\phi$ = {phi[i]:.2f}")
        ax[2].fill_between(b["F"], b["H_low"][:, i], b["H_high"][:, i], color=line.get_color(), alpha=0.2)
        if data is not None:
            fitted = data["fitted"] == 1
            finite = np.isfinite(data["H"][:, j]) & np.isfinite(data["H_sigma"][:, j])
            for mask, marker in ((fitted & finite, "o"), (~fitted & finite, "s")):
                if not mask.any():
                    continue
                ax[2].errorbar(data["F"][mask], data["H"][mask, j], yerr=1.96 * data["H_sigma"][mask, j], fmt=marker,
                               ms=3, color=line.get_color(), mfc=None if marker == "o" else "none")
        ax[2].plot(F, rh(phi[i]) / (1 + ra(phi[i]) * F), "--", color=line.get_color(), lw=0.8)
    ax[2].set(xscale="log", xlabel=r"F = L$_{char}/\Delta$", ylabel=r"H = 1 - $\bar\beta/\beta_{micro}$",
              title="H against F (squares: not fitted; dashed: Radl 2014)")
    ax[2].legend(fontsize=8)
    cv_text = f"{cv:.3g}" if np.isfinite(cv) else "n/a (one run)"
    fig.suptitle(f"{os.path.basename(args.model)}: base law {base}, leave-one-run-out CV rms of H = {cv_text}")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
