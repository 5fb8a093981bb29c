#!/usr/bin/env python3
"""Render a cgd snapshot to a PNG without a GUI: see the clusters of a run at a glance.

Two panels side by side, lengths in primary diameters d_p, gravity pointing down the page:
  left   the particles of a thin slab across z (default 6 d_p thick, at mid-depth), seen along z,
         each drawn to scale and coloured by its vertical velocity v_y (m/s), its speed |v| (m/s)
         or the local solids fraction phi = 1 - eps of its fluid cell (--color);
  right  the void fraction eps of the fluid cells in the layer of cells through the slab's centre
         (absent for a dry run, which has no fluid grid).

    tools/render_snapshot.py out/generate/<scene>/snapshots/snap_000001000.h5 -o snapshot.png
    tools/render_snapshot.py out/generate/<scene> -o last.png        # the run's latest snapshot
    tools/render_snapshot.py RUN_DIR -o phi.png --color phi --slab 10

The picture is drawn with matplotlib (Debian: python3-matplotlib). For 3D views, every frame and every
field, open the run's run.xmf in ParaView: it lists every dataset of every snapshot (docs/schema.md).

Exit status: 0 done; 2 bad input (no such file or run directory, not a snapshot, a slab outside the
box, an unknown option), with a message naming the file or option and what is allowed.
Needs h5py, numpy and matplotlib (Debian: python3-h5py python3-numpy python3-matplotlib).
"""

import argparse
import glob
import os
import sys

try:
    import h5py
    import numpy as np
    import matplotlib  # noqa: F401 (drawn with in render_matplotlib)
except ImportError as missing:
    # `python3` on PATH may not be Debian's; its python3-h5py/python3-matplotlib live with /usr/bin/python3.
    system_python = "/usr/bin/python3"
    if os.path.realpath(sys.executable) != os.path.realpath(system_python) and os.path.exists(system_python) \
            and not os.environ.get("CGD_RENDER_REEXEC"):
        os.environ["CGD_RENDER_REEXEC"] = "1"
        os.execv(system_python, [system_python, os.path.abspath(__file__)] + sys.argv[1:])
    sys.stderr.write(f"render_snapshot.py: needs h5py, numpy and matplotlib ({missing}); "
                     "apt-get install python3-h5py python3-numpy python3-matplotlib\n")
    sys.exit(2)

COLOR_CHOICES = ("vy", "speed", "phi")


class BadInput(Exception):
    """The input cannot be rendered (exit status 2)."""


def find_snapshot(path):
    """The snapshot file `path`, or the latest snapshot of the run directory `path`."""
    if os.path.isdir(path):
        snapshots = sorted(glob.glob(os.path.join(path, "snapshots", "snap_*.h5")))
        if not snapshots:
            raise BadInput(f"{path}: a directory without snapshots/snap_*.h5 "
                           "(expected a run directory of cgd-generate or cgd-coarse, or a snapshot file)")
        return snapshots[-1]
    if not os.path.exists(path):
        raise BadInput(f"{path}: no such file or directory (expected a snapshot file or a run directory)")
    return path


def text(value):
    return value.decode() if isinstance(value, bytes) else str(value)


def read_snapshot(path):
    """Particles, fluid (or None) and the parameters of a snapshot, as numpy arrays in SI units."""
    try:
        f = h5py.File(path, "r")
    except OSError as error:
        raise BadInput(f"{path}: cannot open as HDF5 ({error})")
    with f:
        kind = text(f.attrs.get("cgd_format", ""))
        if kind != "snapshot":
            raise BadInput(f"{path}: cgd_format = {kind!r}, expected 'snapshot' "
                           "(a file of out/<stage>/<scene>/snapshots/)")
        params = {k: f["params"].attrs[k] for k in f["params"].attrs}
        particles = {name: f["particles"][name][...] for name in ("position", "velocity", "diameter")}
        fluid = None
        if "fluid" in f:
            g = f["fluid"]
            fluid = {"void_fraction": g["void_fraction"][...],  # (n_z, n_y, n_x)
                     "spacing": np.asarray(g.attrs["spacing"], dtype=float),  # (x, y, z)
                     "origin": np.asarray(g.attrs["origin"], dtype=float)}
        return {"time": float(f.attrs["time"]), "step": int(f.attrs["step"]), "params": params,
                "particles": particles, "fluid": fluid}


def cell_index(position, fluid):
    """(i_x, i_y, i_z) of the fluid cell holding each position (periodic box)."""
    n = np.array(fluid["void_fraction"].shape[::-1])  # (n_x, n_y, n_z)
    index = np.floor((position - fluid["origin"]) / fluid["spacing"]).astype(int)
    return np.mod(index, n)


def picture(snapshot, color, slab_dp, slab_center_dp):
    """What both backends draw: the particles of the slab (in d_p) with their colour values and scale, the
    void-fraction layer through the slab (or None) and the texts. Raises BadInput for a slab outside the
    box or --color phi without a fluid."""
    params = snapshot["params"]
    d = float(params["diameter_m"])
    box = np.asarray(params["box_size_m"], dtype=float)
    box_dp = box / d
    center_dp = box_dp[2] / 2 if slab_center_dp is None else slab_center_dp
    if not 0 <= center_dp <= box_dp[2]:
        raise BadInput(f"--slab-center {center_dp:g}: outside the box, whose depth is {box_dp[2]:g} d_p "
                       f"(allowed: 0 to {box_dp[2]:g})")
    if not 0 < slab_dp <= box_dp[2]:
        raise BadInput(f"--slab {slab_dp:g}: the slab must be thicker than 0 and at most the box depth "
                       f"{box_dp[2]:g} d_p")
    fluid = snapshot["fluid"]
    if color == "phi" and fluid is None:
        raise BadInput("--color phi: the snapshot has no fluid grid (a dry run); use --color vy or speed")

    x = snapshot["particles"]["position"]
    v = snapshot["particles"]["velocity"]
    z_dp = np.mod(x[:, 2], box[2]) / d
    dz = np.abs((z_dp - center_dp + box_dp[2] / 2) % box_dp[2] - box_dp[2] / 2)  # the slab, periodic in z
    in_slab = dz <= slab_dp / 2
    pic = {"box_dp": box_dp, "xs": np.mod(x[in_slab, 0], box[0]) / d, "ys": np.mod(x[in_slab, 1], box[1]) / d,
           "zs": z_dp[in_slab], "sizes": snapshot["particles"]["diameter"][in_slab] / d}

    u_t = float(params.get("u_t_m_s", 0.0))
    if color == "vy":
        values = v[in_slab, 1]
        limit = np.percentile(np.abs(values), 99) if values.size else 1.0
        pic.update(values=values, label=("particle velocity $v_y$ (m/s)", "v_y (m/s)"), cmap="coolwarm",
                   vmin=-limit, vmax=limit)
    elif color == "speed":
        values = np.linalg.norm(v[in_slab], axis=1)
        pic.update(values=values, label=("particle speed $|v|$ (m/s)", "|v| (m/s)"), cmap="viridis",
                   vmin=0.0, vmax=np.percentile(values, 99) if values.size else 1.0)
    else:
        i = cell_index(x[in_slab], fluid)
        values = 1.0 - fluid["void_fraction"][i[:, 2], i[:, 1], i[:, 0]]
        pic.update(values=values, cmap="magma_r", vmin=0.0, vmax=max(values.max() if values.size else 0.0, 1e-3),
                   label=(r"solids fraction $\phi = 1-\varepsilon$ of the particle's cell (1)", "phi of the cell (1)"))
    if color != "phi" and u_t > 0:  # the scale of the run's velocities
        pic["label"] = (pic["label"][0] + f"; $u_t$ = {u_t:.3g} m/s", pic["label"][1] + f", u_t = {u_t:.3g} m/s")
    pic["particles_title"] = (f"particles, {slab_dp:g} $d_p$ slab at $z$ = {center_dp:g} $d_p$\n"
                              f"({in_slab.sum()} of {len(x)})")

    pic["eps"] = None
    if fluid is not None:
        eps = fluid["void_fraction"]
        spacing_dp = fluid["spacing"] / d
        k = int(np.floor((center_dp * d - fluid["origin"][2]) / fluid["spacing"][2])) % eps.shape[0]
        layer = eps[k]  # (n_y, n_x)
        origin_dp = fluid["origin"] / d
        pic["eps"] = layer
        pic["eps_origin_dp"], pic["eps_spacing_dp"] = origin_dp, spacing_dp
        pic["eps_extent"] = [origin_dp[0], origin_dp[0] + layer.shape[1] * spacing_dp[0],
                             origin_dp[1], origin_dp[1] + layer.shape[0] * spacing_dp[1]]
        pic["eps_range"] = (min(layer.min(), 1.0 - 1e-3), 1.0)
        pic["eps_title"] = (f"void fraction, cell layer {k} of {eps.shape[0]}\n"
                            f"($z$ = {k * spacing_dp[2]:.3g} to {(k + 1) * spacing_dp[2]:.3g} $d_p$)")

    scene = text(params.get("scene_name", ""))
    t_ref = float(params.get("t_ref_s", 0.0))
    when = f"t = {snapshot['time']:.4g} s" + (f" = {snapshot['time'] / t_ref:.3g} $t_{{ref}}$" if t_ref > 0 else "")
    phi = float(params.get("solids_fraction", 0.0))
    pic["title"] = f"{scene}, $\\langle\\phi\\rangle$ = {phi:g}\n{when} (step {snapshot['step']})"
    return pic


def render_matplotlib(pic, out_path):
    """The two panels with matplotlib (Agg: no display)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import EllipseCollection

    box_dp = pic["box_dp"]
    panels = 2 if pic["eps"] is not None else 1
    aspect = box_dp[1] / box_dp[0]  # a tall box: the vertical is the long axis
    axes_height = 7.0 if aspect >= 2 else 4.5  # inches
    axes_width = min(axes_height / aspect, 6.0)
    # fixed margins in inches (y label, colour bar and its label), so labels never overlap
    left, bar_gap, bar_width, bar_label, bottom, top = 0.8, 0.12, 0.16, 0.95, 0.6, 1.1
    panel_width = left + axes_width + bar_gap + bar_width + bar_label
    fig = plt.figure(figsize=(panels * panel_width, bottom + axes_height + top))
    fig_w, fig_h = fig.get_size_inches()

    def panel(i):
        x0 = i * panel_width + left
        ax = fig.add_axes([x0 / fig_w, bottom / fig_h, axes_width / fig_w, axes_height / fig_h])
        cax = fig.add_axes([(x0 + axes_width + bar_gap) / fig_w, (bottom + 0.1 * axes_height) / fig_h,
                            bar_width / fig_w, 0.8 * axes_height / fig_h])
        return ax, cax

    ax, cax = panel(0)
    sizes = pic["sizes"]
    circles = EllipseCollection(sizes, sizes, np.zeros_like(sizes), units="xy",
                                offsets=np.column_stack([pic["xs"], pic["ys"]]), offset_transform=ax.transData,
                                cmap=pic["cmap"], linewidths=0)
    circles.set_array(pic["values"])
    circles.set_clim(pic["vmin"], pic["vmax"])
    ax.add_collection(circles)
    ax.set_xlim(0, box_dp[0])
    ax.set_ylim(0, box_dp[1])
    ax.set_aspect("equal")
    ax.set_xlabel("$x / d_p$")
    ax.set_ylabel("$y / d_p$ (vertical, gravity down)")
    ax.set_title(pic["particles_title"], fontsize=9)
    fig.colorbar(circles, cax=cax).set_label(pic["label"][0])

    if pic["eps"] is not None:
        ax2, cax2 = panel(1)
        image = ax2.imshow(pic["eps"], origin="lower", extent=pic["eps_extent"], cmap="cividis",
                           interpolation="nearest", vmin=pic["eps_range"][0], vmax=pic["eps_range"][1])
        ax2.set_aspect("equal")
        ax2.set_xlabel("$x / d_p$")
        ax2.set_ylabel("$y / d_p$")
        ax2.set_title(pic["eps_title"], fontsize=9)
        fig.colorbar(image, cax=cax2).set_label(r"void fraction $\varepsilon$ (1)")

    fig.suptitle(pic["title"], fontsize=10, y=1 - 0.08 / fig_h, va="top")
    try:
        fig.savefig(out_path, dpi=150)
    except OSError as error:
        raise BadInput(f"-o {out_path}: cannot write ({error.strerror or error})")
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(
        description="Render a cgd snapshot to PNG (particles of a thin slab coloured by velocity or local "
                    "solids fraction, and a slice of the void fraction), headless, with matplotlib.")
    parser.add_argument("snapshot", help="a snapshot file (snapshots/snap_*.h5) or a run directory (its latest "
                                         "snapshot)")
    parser.add_argument("-o", "--output", required=True, help="the PNG to write")
    parser.add_argument("--color", choices=COLOR_CHOICES, default="vy",
                        help="colour of the particles: vy (vertical velocity, m/s; default), speed (m/s), "
                             "phi (solids fraction of the particle's fluid cell)")
    parser.add_argument("--slab", type=float, default=6.0, metavar="D_P",
                        help="thickness of the slab of particles along z, in d_p (default 6)")
    parser.add_argument("--slab-center", type=float, default=None, metavar="D_P",
                        help="z of the slab's centre in d_p (default: mid-depth)")
    args = parser.parse_args(argv)
    try:
        path = find_snapshot(args.snapshot)
        render_matplotlib(picture(read_snapshot(path), args.color, args.slab, args.slab_center), args.output)
    except BadInput as error:
        sys.stderr.write(f"render_snapshot.py: error: {error}\n")
        return 2
    print(f"render_snapshot.py: {path} -> {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
