#!/usr/bin/env python3
"""Inspect a cgd HDF5 file: header, key parameters, datasets and summary statistics.

Works for every cgd file (cgd_format snapshot, series, checkpoint, filtered, drag_model); the
statistics are specific to snapshots (particles, fluid) and series (columns, first/last rows).

    tools/inspect_snapshot.py out/generate/<scene>/snapshots/snap_000001000.h5
    tools/inspect_snapshot.py --json out/generate/<scene>/series.h5

Exit status: 0 done; 2 the file is missing, unreadable or not a cgd file.
Needs only h5py and numpy (Debian: python3-h5py python3-numpy).
"""

import argparse
import json
import math
import os
import sys

try:
    import h5py
    import numpy as np
except ImportError as missing:
    from system_python import reexec_or_exit
    reexec_or_exit(__file__, missing, ["python3-h5py", "python3-numpy"])

# /params attributes shown by default (all of them with --all-params).
KEY_PARAMS = [
    "scene_name", "diameter_m", "density_kg_m3", "solids_fraction", "parcel_size", "box_size_m",
    "gravity_m_s2", "particle_count", "contact_model", "restitution", "friction", "k_n_N_m", "t_c_s",
    "dt_dem_s", "coupling", "drag", "cells", "dt_fluid_s", "u_t_m_s", "re_p", "fr_p", "l_char_m",
    "t_ref_s",
]

MAX_PAIR_SEARCH = 200_000  # particles; above this the pair search is skipped


class BadFile(Exception):
    """The file cannot be inspected (exit status 2)."""


def plain(value):
    """An attribute or numpy value as plain Python (str, int, float, list) for printing and JSON."""
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray):
        return [plain(v) for v in value.tolist()] if value.ndim else plain(value.item())
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (np.floating,)):
        return float(value)
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    return value


def fmt(value):
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        return "[" + ", ".join(fmt(v) for v in value) + "]"
    return str(value)


def stats(array):
    a = np.asarray(array, dtype=np.float64)
    if a.size == 0:
        return {"min": None, "max": None, "mean": None}
    return {"min": float(a.min()), "max": float(a.max()), "mean": float(a.mean())}


# ---- particles ------------------------------------------------------------------------------------

def neighbour_offsets(n_cells):
    """Distinct periodic neighbour-cell offsets per axis (fewer than 3 cells: no duplicates)."""
    per_axis = [sorted({(o % n) for o in (-1, 0, 1)}) for n in n_cells]
    return [(a, b, c) for a in per_axis[0] for b in per_axis[1] for c in per_axis[2]]


def closest_pairs(position, diameter, box):
    """Minimum centre distance and maximum overlap over all pairs closer than the largest diameter,
    periodic in `box`, with a uniform cell grid (numpy only). Returns a dict."""
    n = len(position)
    cutoff = float(diameter.max())
    if n < 2 or cutoff <= 0:
        return {"pairs_checked": 0}
    box = np.asarray(box, dtype=np.float64)
    pos = np.mod(position, box)
    n_cells = np.maximum(1, np.floor(box / cutoff).astype(np.int64))
    cell = np.minimum((pos / (box / n_cells)).astype(np.int64), n_cells - 1)
    linear = (cell[:, 2] * n_cells[1] + cell[:, 1]) * n_cells[0] + cell[:, 0]
    order = np.argsort(linear, kind="stable")
    sorted_linear = linear[order]
    total_cells = int(np.prod(n_cells))
    start = np.searchsorted(sorted_linear, np.arange(total_cells), side="left")
    end = np.searchsorted(sorted_linear, np.arange(total_cells), side="right")

    best_distance = math.inf
    best_overlap = -math.inf
    overlapping = 0
    checked = 0
    for off in neighbour_offsets(n_cells):
        nb = np.mod(cell + np.asarray(off), n_cells)
        nb_linear = (nb[:, 2] * n_cells[1] + nb[:, 1]) * n_cells[0] + nb[:, 0]
        counts = end[nb_linear] - start[nb_linear]
        if counts.sum() == 0:
            continue
        i = np.repeat(np.arange(n), counts)
        first = np.repeat(start[nb_linear], counts)
        within = np.arange(len(i)) - np.repeat(np.cumsum(counts) - counts, counts)
        j = order[first + within]
        keep = i < j  # each unordered pair once, no self pairs
        i, j = i[keep], j[keep]
        if len(i) == 0:
            continue
        d = pos[j] - pos[i]
        d -= box * np.round(d / box)
        dist = np.sqrt((d * d).sum(axis=1))
        overlap = 0.5 * (diameter[i] + diameter[j]) - dist
        checked += len(i)
        best_distance = min(best_distance, float(dist.min()))
        best_overlap = max(best_overlap, float(overlap.max()))
        overlapping += int((overlap > 0).sum())
    # Every pair closer than `cutoff` is among those checked (cells are at least `cutoff` wide), so
    # overlaps are exact; a nearest distance beyond `cutoff` is not (farther cells were not searched).
    result = {"pairs_checked": checked, "search_radius_m": cutoff, "max_overlap_m": max(best_overlap, 0.0),
              "max_overlap_over_d": max(best_overlap, 0.0) / float(diameter.mean()),
              "overlapping_pairs": overlapping}
    if best_distance <= cutoff:
        result["min_pair_distance_m"] = best_distance
    return result


def particle_summary(f, box):
    g = f["particles"]
    out = {}
    n = g["id"].shape[0] if "id" in g else (g["position"].shape[0] if "position" in g else 0)
    out["count"] = int(n)
    if "velocity" in g and n:
        v = g["velocity"][...]
        out["velocity_mean_m_s"] = v.mean(axis=0).tolist()
        out["velocity_rms_m_s"] = np.sqrt((v * v).mean(axis=0)).tolist()
        out["velocity_fluctuation_rms_m_s"] = v.std(axis=0).tolist()
    if "angular_velocity" in g and n:
        w = g["angular_velocity"][...]
        out["angular_velocity_rms_rad_s"] = np.sqrt((w * w).mean(axis=0)).tolist()
    if "diameter" in g and n:
        d = g["diameter"][...]
        out["diameter_m"] = stats(d)
        if box is not None:
            volume = float(np.prod(box))
            out["solids_fraction"] = float((np.pi / 6.0 * d ** 3).sum() / volume) if volume > 0 else None
        if "position" in g and box is not None:
            if n <= MAX_PAIR_SEARCH:
                out["pairs"] = closest_pairs(g["position"][...], d, box)
            else:
                out["pairs"] = {"skipped": f"more than {MAX_PAIR_SEARCH} particles"}
    for name in ("drag_coefficient",):
        if name in g and n:
            out[name] = stats(g[name][...])
    if "pressure_gradient_mean" in g.attrs:
        out["pressure_gradient_mean_Pa_m"] = plain(g.attrs["pressure_gradient_mean"])
    return out


def fluid_summary(f):
    g = f["fluid"]
    out = {k: plain(g.attrs[k]) for k in ("cells", "spacing", "origin") if k in g.attrs}
    for name in ("void_fraction", "pressure"):
        if name in g:
            out[name] = stats(g[name][...])
    if "void_fraction" in g:
        out["solids_fraction_from_grid"] = 1.0 - out["void_fraction"]["mean"] if g["void_fraction"].size else None
    if "velocity" in g:
        u = g["velocity"][...].reshape(-1, 3)
        out["velocity"] = {axis: stats(u[:, k]) for k, axis in enumerate("xyz")}
    return out


def series_summary(f):
    columns = [plain(c) for c in f.attrs.get("columns", [])] or sorted(
        k for k in f.keys() if isinstance(f[k], h5py.Dataset))
    out = {"columns": [], "rows": 0, "first_row": {}, "last_row": {}}
    for name in columns:
        if name not in f:
            continue
        ds = f[name]
        unit = plain(ds.attrs.get("unit", ""))
        width = 1 if ds.ndim == 1 else int(ds.shape[1])
        out["columns"].append({"name": name, "width": width, "unit": unit})
        out["rows"] = int(ds.shape[0])
        if ds.shape[0]:
            out["first_row"][name] = plain(ds[0])
            out["last_row"][name] = plain(ds[-1])
    return out


# ---- the whole file ----------------------------------------------------------------------------------

def inspect(path, all_params=False):
    if os.path.isdir(path):
        raise BadFile(f"{path}: is a directory, not an HDF5 file")
    try:
        f = h5py.File(path, "r")
    except FileNotFoundError:
        raise BadFile(f"{path}: no such file")
    except (OSError, ValueError) as e:
        raise BadFile(f"{path}: cannot open as HDF5 ({e})")
    with f:
        if "cgd_format" not in f.attrs:
            raise BadFile(f"{path}: not a cgd file (no cgd_format attribute)")
        info = {"file": path}
        for key in ("cgd_format", "cgd_format_version", "code_version", "created", "time", "step"):
            if key in f.attrs:
                info[key] = plain(f.attrs[key])
        if "params" in f:
            attrs = f["params"].attrs
            keys = sorted(attrs.keys()) if all_params else [k for k in KEY_PARAMS if k in attrs]
            info["params"] = {k: plain(attrs[k]) for k in keys}
        datasets = {}

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                datasets["/" + name] = {"shape": list(obj.shape), "dtype": str(obj.dtype)}

        f.visititems(visit)
        info["datasets"] = datasets
        box = None
        if "params" in f and "box_size_m" in f["params"].attrs:
            box = np.asarray(f["params"].attrs["box_size_m"], dtype=np.float64)
        if "particles" in f:
            info["particles"] = particle_summary(f, box)
        if "fluid" in f:
            info["fluid"] = fluid_summary(f)
        if info.get("cgd_format") == "series":
            info["series"] = series_summary(f)
        return info


def print_report(info, out=sys.stdout):
    w = out.write
    w(f"{info['file']}\n")
    w(f"  format        {info.get('cgd_format')} (version {info.get('cgd_format_version')})\n")
    w(f"  code version  {info.get('code_version')}\n")
    w(f"  created       {info.get('created')}\n")
    if "time" in info or "step" in info:
        w(f"  time          {fmt(info.get('time'))} s, step {info.get('step')}\n")
    if info.get("params"):
        w("params\n")
        for k, v in info["params"].items():
            w(f"  {k:<24}{fmt(v)}\n")
    w("datasets\n")
    for name, d in info["datasets"].items():
        shape = "x".join(str(s) for s in d["shape"]) or "scalar"
        w(f"  {name:<32}{shape:<16}{d['dtype']}\n")
    p = info.get("particles")
    if p:
        w("particles\n")
        w(f"  count                   {p['count']}\n")
        for key, label in (("velocity_mean_m_s", "velocity mean (m/s)"),
                           ("velocity_rms_m_s", "velocity rms (m/s)"),
                           ("velocity_fluctuation_rms_m_s", "velocity fluct. rms"),
                           ("angular_velocity_rms_rad_s", "ang. velocity rms")):
            if key in p:
                w(f"  {label:<24}{fmt(p[key])}\n")
        if "diameter_m" in p:
            d = p["diameter_m"]
            w(f"  diameter (m)            min {fmt(d['min'])}  max {fmt(d['max'])}  mean {fmt(d['mean'])}\n")
        if p.get("solids_fraction") is not None:
            w(f"  solids fraction         {fmt(p['solids_fraction'])} (particle volume / box)\n")
        pairs = p.get("pairs")
        if pairs:
            if "skipped" in pairs:
                w(f"  pair search             skipped ({pairs['skipped']})\n")
            elif "search_radius_m" in pairs:
                if "min_pair_distance_m" in pairs:
                    w(f"  min pair distance (m)   {fmt(pairs['min_pair_distance_m'])}\n")
                else:
                    w(f"  min pair distance       none closer than {fmt(pairs['search_radius_m'])} m\n")
                w(f"  max overlap (m)         {fmt(pairs['max_overlap_m'])} "
                  f"({fmt(100 * pairs['max_overlap_over_d'])} % of d), {pairs['overlapping_pairs']} overlapping pairs\n")
        if "drag_coefficient" in p:
            d = p["drag_coefficient"]
            w(f"  drag coefficient        min {fmt(d['min'])}  max {fmt(d['max'])}  mean {fmt(d['mean'])}\n")
    fl = info.get("fluid")
    if fl:
        w("fluid\n")
        for k in ("cells", "spacing", "origin"):
            if k in fl:
                w(f"  {k:<24}{fmt(fl[k])}\n")
        for k in ("void_fraction", "pressure"):
            if k in fl:
                s = fl[k]
                w(f"  {k:<24}min {fmt(s['min'])}  max {fmt(s['max'])}  mean {fmt(s['mean'])}\n")
        if "velocity" in fl:
            for axis, s in fl["velocity"].items():
                w(f"  {'velocity ' + axis:<24}min {fmt(s['min'])}  max {fmt(s['max'])}  mean {fmt(s['mean'])}\n")
        if fl.get("solids_fraction_from_grid") is not None:
            w(f"  solids fraction (grid)  {fmt(fl['solids_fraction_from_grid'])}\n")
    s = info.get("series")
    if s:
        w(f"series: {s['rows']} rows\n")
        for c in s["columns"]:
            w(f"  {c['name']:<28}width {c['width']:<3} [{c['unit']}]\n")
        for label in ("first_row", "last_row"):
            if s[label]:
                w(f"{label.replace('_', ' ')}\n")
                for k, v in s[label].items():
                    w(f"  {k:<28}{fmt(v)}\n")


def main(argv=None):
    parser = argparse.ArgumentParser(description="Inspect a cgd HDF5 file (snapshot, series, ...).")
    parser.add_argument("file", help="a cgd HDF5 file")
    parser.add_argument("--json", action="store_true", help="print a machine-readable summary (JSON)")
    parser.add_argument("--all-params", action="store_true", help="print every /params attribute")
    args = parser.parse_args(argv)
    try:
        info = inspect(args.file, all_params=args.all_params)
    except BadFile as e:
        sys.stderr.write(f"inspect_snapshot.py: {e}\n")
        return 2
    except (OSError, KeyError, ValueError) as e:
        sys.stderr.write(f"inspect_snapshot.py: {args.file}: unreadable ({e})\n")
        return 2
    try:
        if args.json:
            json.dump(info, sys.stdout, indent=2, default=plain)
            sys.stdout.write("\n")
        else:
            print_report(info)
        sys.stdout.flush()
    except BrokenPipeError:  # e.g. piped into `head`
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


if __name__ == "__main__":
    sys.exit(main())
