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

Two backends draw the same picture (--backend): ParaView (Debian's python3-paraview, the module behind
pvpython; particles as spheres) when it is installed, and matplotlib (python3-matplotlib) otherwise, or
when ParaView fails. Debian builds ParaView to draw through X, so without a display the tool starts a
virtual one (Xvfb, Debian: xvfb) for the drawing and stops it after. For 3D views, every frame and
every field, open the run's run.xmf in ParaView: it lists every dataset of every snapshot.

Exit status: 0 done; 2 bad input (no such file or run directory, not a snapshot, a slab outside the
box, an unknown option), with a message naming the file or option and what is allowed.
Needs h5py, numpy and matplotlib (Debian: python3-h5py python3-numpy python3-matplotlib); ParaView is
optional (python3-paraview xvfb).
"""

import argparse
import glob
import os
import shutil
import subprocess
import sys

try:
    import h5py
    import numpy as np
    import matplotlib  # noqa: F401 (drawn with in render_matplotlib)
except ImportError as missing:
    from system_python import reexec_or_exit
    reexec_or_exit(__file__, missing, ["python3-h5py", "python3-numpy", "python3-matplotlib"])

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
    pic["particles_title_plain"] = f"particles: {slab_dp:g} d_p slab at z = {center_dp:g} d_p ({in_slab.sum()} of {len(x)})"

    pic["eps"] = None
    if fluid is not None:
        eps = fluid["void_fraction"]
        spacing_dp = fluid["spacing"] / d
        k = int(np.floor((center_dp * d - fluid["origin"][2]) / fluid["spacing"][2])) % eps.shape[0]
        layer = eps[k]  # (n_y, n_x)
        origin_dp = fluid["origin"] / d
        pic["eps"] = layer
        pic["eps_origin_dp"], pic["eps_spacing_dp"] = origin_dp, spacing_dp
        pic["eps_z_dp"] = origin_dp[2] + k * spacing_dp[2]
        pic["eps_extent"] = [origin_dp[0], origin_dp[0] + layer.shape[1] * spacing_dp[0],
                             origin_dp[1], origin_dp[1] + layer.shape[0] * spacing_dp[1]]
        pic["eps_range"] = (min(layer.min(), 1.0 - 1e-3), 1.0)
        pic["eps_title"] = (f"void fraction, cell layer {k} of {eps.shape[0]}\n"
                            f"($z$ = {k * spacing_dp[2]:.3g} to {(k + 1) * spacing_dp[2]:.3g} $d_p$)")
        pic["eps_title_plain"] = (f"void fraction: cell layer {k} of {eps.shape[0]} "
                                  f"(z = {k * spacing_dp[2]:.3g} to {(k + 1) * spacing_dp[2]:.3g} d_p)")

    scene = text(params.get("scene_name", ""))
    t_ref = float(params.get("t_ref_s", 0.0))
    when = f"t = {snapshot['time']:.4g} s" + (f" = {snapshot['time'] / t_ref:.3g} $t_{{ref}}$" if t_ref > 0 else "")
    phi = float(params.get("solids_fraction", 0.0))
    pic["title"] = f"{scene}, $\\langle\\phi\\rangle$ = {phi:g}\n{when} (step {snapshot['step']})"
    pic["title_plain"] = (f"{scene}, <phi> = {phi:g}, " + when.replace("$t_{ref}$", "t_ref") +
                          f" (step {snapshot['step']})")
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


# ParaView's names of the matplotlib colour maps used above
PARAVIEW_PRESETS = {"coolwarm": "Cool to Warm", "viridis": "Viridis (matplotlib)", "magma_r": "Magma (matplotlib)",
                    "cividis": "Cividis"}


def render_paraview(pic, out_path):
    """The same two panels with ParaView (Debian's python3-paraview, the module behind pvpython): the
    particles as spheres to scale, the void-fraction layer as cells, side by side in one layout, seen
    along z with a parallel projection. Needs a display (an X server, or Xvfb: see main)."""
    from paraview import simple as pv
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPolyData
    from vtkmodules.util.numpy_support import numpy_to_vtk

    def vtk_array(values, name):
        array = numpy_to_vtk(np.ascontiguousarray(values, dtype=float), deep=1)
        array.SetName(name)
        return array

    def source(data):
        producer = pv.TrivialProducer()
        producer.GetClientSideObject().SetOutput(data)
        return producer

    box_dp = pic["box_dp"]
    layout = pv.CreateLayout("snapshot")

    def view(hint, title):
        v = pv.CreateView("RenderView")
        pv.AssignViewToLayout(view=v, layout=layout, hint=hint)
        v.OrientationAxesVisibility = 0
        v.UseColorPaletteForBackground = 0
        v.Background = [1.0, 1.0, 1.0]
        v.CameraParallelProjection = 1
        label = pv.Text(Text=title)
        shown = pv.Show(label, v)
        shown.Color, shown.FontSize, shown.WindowLocation = [0.0, 0.0, 0.0], 13, "Upper Center"
        return v

    def look_along_z(v):
        """Seen along -z, gravity down the page, the box left of centre and the colour bar right of it.
        The camera is reset to the data first, which also sets the clipping range the axes labels need."""
        v.CameraPosition, v.CameraFocalPoint, v.CameraViewUp = [0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]
        pv.ResetCamera(v)
        camera = v.GetActiveCamera()
        distance = camera.GetDistance()
        center = [0.85 * box_dp[0], 0.5 * box_dp[1], camera.GetFocalPoint()[2]]
        camera.SetFocalPoint(*center)
        camera.SetPosition(center[0], center[1], center[2] + distance)
        camera.SetParallelScale(0.58 * max(box_dp[1], 1.6 * box_dp[0]))
        grid = v.AxesGrid  # after the data: the labels are placed on the data's bounds
        grid.Visibility = 1
        grid.AxesToLabel = 1 | 2  # the min-x and min-y edges only: bottom and left, clear of the title
        grid.XTitle, grid.YTitle = "x / d_p", "y / d_p"
        for name in ("XTitleColor", "YTitleColor", "XLabelColor", "YLabelColor", "GridColor"):
            setattr(grid, name, [0.0, 0.0, 0.0])

    def colour(v, shown, association, name, preset, value_range, title):
        pv.ColorBy(shown, (association, name))
        lut = pv.GetColorTransferFunction(name)
        lut.ApplyPreset(preset, True)
        lut.RescaleTransferFunction(*value_range)
        shown.SetScalarBarVisibility(v, True)
        bar = pv.GetScalarBar(lut, v)
        bar.Title, bar.ComponentTitle = title, ""
        bar.TitleColor = bar.LabelColor = [0.0, 0.0, 0.0]
        bar.TitleFontSize, bar.LabelFontSize = 14, 12
        bar.WindowLocation, bar.Position, bar.ScalarBarLength = "Any Location", [0.75, 0.12], 0.7
        bar.AutomaticLabelFormat, bar.LabelFormat, bar.RangeLabelFormat = 0, "%-#.3g", "%-#.3g"

    particles = vtkPolyData()
    points = vtkPoints()
    points.SetData(vtk_array(np.column_stack([pic["xs"], pic["ys"], pic["zs"]]), "position"))
    particles.SetPoints(points)
    particles.GetPointData().AddArray(vtk_array(pic["values"], "value"))
    particles.GetPointData().AddArray(vtk_array(pic["sizes"], "diameter"))
    spheres = pv.Glyph(Input=source(particles), GlyphType="Sphere")
    spheres.ScaleArray, spheres.ScaleFactor, spheres.GlyphMode = ["POINTS", "diameter"], 1.0, "All Points"
    spheres.GlyphType.Radius, spheres.GlyphType.ThetaResolution, spheres.GlyphType.PhiResolution = 0.5, 12, 8
    left = view(0, pic["title_plain"] + "\n" + pic["particles_title_plain"])
    colour(left, pv.Show(spheres, left), "POINTS", "value", PARAVIEW_PRESETS[pic["cmap"]],
           (pic["vmin"], pic["vmax"]), pic["label"][1])
    look_along_z(left)

    if pic["eps"] is not None:
        layout.SplitHorizontal(0, 0.5)
        layer = vtkImageData()
        ny, nx = pic["eps"].shape
        layer.SetDimensions(nx + 1, ny + 1, 2)  # one cell thick: a box the axes grid can label
        layer.SetOrigin(pic["eps_origin_dp"][0], pic["eps_origin_dp"][1], pic["eps_z_dp"])
        layer.SetSpacing(*pic["eps_spacing_dp"])
        layer.GetCellData().AddArray(vtk_array(pic["eps"].ravel(), "void_fraction"))
        right = view(2, "\n" + pic["eps_title_plain"])
        shown = pv.Show(source(layer), right)
        shown.Representation = "Surface"
        shown.Ambient, shown.Diffuse = 1.0, 0.0  # unlit: the cells' colours are the colour bar's
        colour(right, shown, "CELLS", "void_fraction", PARAVIEW_PRESETS["cividis"], pic["eps_range"],
               "void fraction (1)")
        look_along_z(right)

    size = [620 * (2 if pic["eps"] is not None else 1), 1100]
    layout.SetSize(*size)  # the picture's own size: a magnified screenshot drops the axes' labels
    if not pv.SaveScreenshot(out_path, layout, ImageResolution=size, FontScaling="Do not scale fonts"):
        raise BadInput(f"-o {out_path}: ParaView could not write it")


def paraview_available():
    """ParaView's Python module is importable and can draw: a display, or Xvfb to make one."""
    try:
        import paraview.simple  # noqa: F401
    except ImportError:
        return False
    return bool(os.environ.get("DISPLAY")) or shutil.which("Xvfb") is not None


def run_with_virtual_display(command):
    """Runs `command` (stderr captured) with DISPLAY on an Xvfb server started for it and stopped after.
    Xvfb -displayfd writes the display number once the server accepts connections (no race with its
    start, which xvfb-run -a has on a loaded machine); -noreset keeps it from resetting when ParaView's
    first probe disconnects (the next connection would fail: "bad X server connection")."""
    read_end, write_end = os.pipe()
    server = subprocess.Popen(["Xvfb", "-displayfd", str(write_end), "-screen", "0", "1600x1200x24", "-noreset",
                               "-nolisten", "tcp"], pass_fds=(write_end,), stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    os.close(write_end)
    try:
        with os.fdopen(read_end) as display:
            number = display.readline().strip()  # empty when the server failed to start
        if not number:
            return subprocess.CompletedProcess(command, 1, "", "Xvfb did not start\n")
        return subprocess.run(command, env=dict(os.environ, DISPLAY=":" + number), stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True)
    finally:
        server.terminate()
        server.wait()


def main(argv=None):
    parser = argparse.ArgumentParser(
        description="Render a cgd snapshot to PNG (particles of a thin slab coloured by velocity or local "
                    "solids fraction, and a slice of the void fraction), headless, with ParaView or matplotlib.")
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
    parser.add_argument("--backend", choices=("auto", "paraview", "matplotlib"), default="auto",
                        help="auto (default): ParaView when Debian's python3-paraview (pvpython) is installed "
                             "and a display or Xvfb is there (ParaView failing, matplotlib), else matplotlib")
    args = parser.parse_args(argv)
    try:
        folder = os.path.dirname(os.path.abspath(args.output))
        if not os.path.isdir(folder) or not os.access(folder, os.W_OK):
            raise BadInput(f"-o {args.output}: cannot write ({folder} is not a writable directory)")
        path = find_snapshot(args.snapshot)
        pic = picture(read_snapshot(path), args.color, args.slab, args.slab_center)
        backend = args.backend
        if backend == "auto":
            backend = "paraview" if paraview_available() else "matplotlib"
        if backend == "paraview" and not os.environ.get("DISPLAY"):
            # ParaView draws through X (Debian builds it without offscreen EGL/OSMesa): give it a virtual one
            if shutil.which("Xvfb") is None:
                raise BadInput("--backend paraview: no display (DISPLAY unset) and no Xvfb to make one "
                               "(apt-get install xvfb), or use --backend matplotlib")
            command = [sys.executable, os.path.abspath(__file__), path, "-o", args.output, "--color", args.color,
                       "--slab", repr(args.slab), "--backend", "paraview"]
            if args.slab_center is not None:
                command += ["--slab-center", repr(args.slab_center)]
            status = run_with_virtual_display(command)
            if status.returncode == 0:
                print(f"render_snapshot.py: {path} -> {args.output} (ParaView)")
                return 0
            if status.returncode == 2 or args.backend == "paraview":
                sys.stderr.write(status.stderr)
                return status.returncode
            sys.stderr.write(f"render_snapshot.py: ParaView failed (exit status {status.returncode}); "
                             "drawing with matplotlib instead\n")
            backend = "matplotlib"
        if backend == "paraview":
            try:
                import paraview.simple  # noqa: F401
            except ImportError:
                raise BadInput("--backend paraview: ParaView's Python module is not installed "
                               "(apt-get install python3-paraview), or use --backend matplotlib")
            render_paraview(pic, args.output)
        else:
            render_matplotlib(pic, args.output)
    except BadInput as error:
        sys.stderr.write(f"render_snapshot.py: error: {error}\n")
        return 2
    print(f"render_snapshot.py: {path} -> {args.output} ({'ParaView' if backend == 'paraview' else 'matplotlib'})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
