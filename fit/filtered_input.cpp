// Reading filtered files for the fitter (see filtered_input.hpp, docs/schema-filtered.md).
#include "fit/filtered_input.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/checksum.hpp"
#include "core/drag.hpp"
#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/output.hpp"

namespace cgd::fit {

namespace {

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

}  // namespace

FilteredFile read_filtered_file(const std::string& path) {
  h5::File f = h5::File::open_read(path, MPI_COMM_SELF);
  auto need_attr = [&](const std::string& object, const char* key) {
    if (!f.has_attr(object, key))
      throw InputError(path + ": filtered file lacks the attribute " + key +
                       (object == "/" ? "" : " of " + object));
  };
  auto need = [&](const std::string& dataset) {
    if (!f.exists(dataset)) throw InputError(path + ": filtered file lacks the dataset " + dataset);
  };
  check_derived_format(f, "filtered", "filtered file", "cgd-fit reads the \"filtered\" files of cgd-filter");
  FilteredFile out;
  out.path = path;
  need_attr("/", "scene");
  out.physics = read_physical_system(f, "micro_drag", "filtered file");
  out.scene_toml = f.attr_string("/", "scene");
  const PhysicalSystem& p = out.physics;
  if (!(p.l_char_m > 0)) throw InputError(path + ": l_char_m = " + number(p.l_char_m) + ": must be > 0");

  need("/bins/phi_edges");
  out.phi_edges = f.read_double("/bins/phi_edges");
  const std::size_t nb = out.bins();
  if (nb < 1 || !std::is_sorted(out.phi_edges.begin(), out.phi_edges.end()))
    throw InputError(path + ": /bins/phi_edges must hold at least two increasing edges");

  // /runs and /snapshots
  need("/runs/mean_solids_fraction");
  out.run_paths =
      f.has_attr("/runs", "paths") ? f.attr_strings("/runs", "paths") : std::vector<std::string>{};
  const std::size_t n_runs = f.dims("/runs/mean_solids_fraction").at(0);
  if (out.run_paths.size() != n_runs) out.run_paths.resize(n_runs, path);
  need("/snapshots/run_index");
  need("/snapshots/block");
  out.snapshot_run = f.read_int("/snapshots/run_index");
  out.snapshot_block = f.read_int("/snapshots/block");
  const std::size_t ns = out.snapshot_run.size();
  if (out.snapshot_block.size() != ns)
    throw InputError(path + ": /snapshots/block and /snapshots/run_index differ in length");
  for (std::int64_t r : out.snapshot_run)
    if (r < 0 || static_cast<std::size_t>(r) >= n_runs)
      throw InputError(path + ": /snapshots/run_index holds " + std::to_string(r) + ", outside [0, " +
                       std::to_string(n_runs) + ")");

  // the widths: /width_0, /width_1, ... then /whole_box
  std::vector<std::string> groups;
  for (int k = 0; f.exists("/width_" + std::to_string(k)); ++k)
    groups.push_back("/width_" + std::to_string(k));
  if (f.exists("/whole_box")) groups.push_back("/whole_box");
  out.has_per_snapshot = !groups.empty() && f.exists(groups.front() + "/per_snapshot/numerator");
  // the coarse grids: /grids/<N> (cgd-filter --grids), cells across descending (ascending cell size)
  std::vector<std::string> grid_groups;
  if (f.exists("/grids") && f.has_attr("/grids", "cells_across"))
    for (std::int64_t n : f.attr_ints("/grids", "cells_across")) {
      const std::string g = "/grids/" + std::to_string(n);
      if (!f.exists(g)) throw InputError(path + ": /grids lists " + std::to_string(n) + " cells across but lacks the group " + g);
      grid_groups.push_back(g);
    }
  const std::size_t n_box_groups = groups.size();
  groups.insert(groups.end(), grid_groups.begin(), grid_groups.end());
  for (std::size_t gi = 0; gi < groups.size(); ++gi) {
    const std::string& g = groups[gi];
    WidthSeries w;
    w.group = g;
    need_attr(g, "F");
    w.F = f.attr_double(g, "F");
    if (f.has_attr(g, "width_m")) w.width_m = f.attr_double(g, "width_m");
    if (f.has_attr(g, "width_over_cell")) w.width_over_cell = f.attr_double(g, "width_over_cell");
    w.whole_box = g == "/whole_box";
    w.grid = gi >= n_box_groups;
    if (w.grid) {
      for (const char* key : {"cells_across", "cell_size_over_dp"}) need_attr(g, key);
      w.cells_across = f.attr_int(g, "cells_across");
      w.cell_size_over_dp = f.attr_double(g, "cell_size_over_dp");
    }
    if (!(w.F > 0)) throw InputError(path + ": " + g + " attribute F = " + number(w.F) + ": must be > 0");
    for (const char* d : {"H", "H_low", "H_high", "count", "phi_mean"}) need(g + "/" + d);
    w.H = f.read_double(g + "/H");
    w.H_low = f.read_double(g + "/H_low");
    w.H_high = f.read_double(g + "/H_high");
    w.phi_mean = f.read_double(g + "/phi_mean");
    w.count = f.read_int(g + "/count");
    for (std::size_t size : {w.H.size(), w.H_low.size(), w.H_high.size(), w.phi_mean.size(), w.count.size()})
      if (size != nb)
        throw InputError(path + ": " + g + ": per-bin datasets must have n_bins = " + std::to_string(nb) +
                         " entries (len(/bins/phi_edges) - 1)");
    if (out.has_per_snapshot) {
      for (const char* d : {"numerator", "micro", "count"}) {
        const std::string ds = g + "/per_snapshot/" + d;
        need(ds);
        const auto dims = f.dims(ds);
        if (dims.size() != 2 || dims[0] != ns || dims[1] != nb)
          throw InputError(path + ": " + ds + " must have shape (n_snapshots, n_bins) = (" +
                           std::to_string(ns) + ", " + std::to_string(nb) + ")");
      }
      w.numerator = f.read_double(g + "/per_snapshot/numerator");
      w.micro = f.read_double(g + "/per_snapshot/micro");
      w.snapshot_count = f.read_int(g + "/per_snapshot/count");
    }
    (w.grid ? out.grids : out.widths).push_back(std::move(w));
  }
  f.close();
  out.checksum = file_checksum_fnv1a(path);
  return out;
}

std::vector<FilteredFile> select_operator(const std::vector<FilteredFile>& files, const std::string& op) {
  if (op == "box") return files;
  if (op != "grid") throw InputError("cgd-fit: --operator " + op + ": allowed \"box\" or \"grid\"");
  std::vector<FilteredFile> out = files;
  for (FilteredFile& f : out) {
    if (f.grids.empty())
      throw InputError(f.path + ": --operator grid needs the coarse grids' H (groups /grids/<N>), and the file has "
                       "none: filter the runs with cgd-filter --grids N1,N2,... (docs/filter.md)");
    // the resolved run's own grid is the identity (H_grid = 0 by construction, zero interval): left out
    std::vector<WidthSeries> series;
    for (const WidthSeries& w : f.grids)
      if (!(w.width_over_cell < 1.0 + 1e-6)) series.push_back(w);
    for (const WidthSeries& w : f.widths)
      if (w.whole_box) series.push_back(w);
    f.widths = std::move(series);
  }
  return out;
}

void check_same_physics(const std::vector<FilteredFile>& files) {
  if (files.empty()) return;
  const FilteredFile& ref = files.front();
  auto same = [](double a, double b) { return std::abs(a - b) <= 1e-6 * std::max(std::abs(a), std::abs(b)); };
  for (std::size_t i = 1; i < files.size(); ++i) {
    const FilteredFile& o = files[i];
    const std::string both = o.path + " and " + ref.path;
    auto differ = [&](const char* key, const std::string& mine, const std::string& theirs) {
      throw InputError(both + " are filtered files of different physics and cannot be pooled: " + key +
                       " = " + mine + " in " + o.path + ", " + theirs + " in " + ref.path);
    };
    if (const auto d = compare_systems(o.physics, ref.physics))
      differ(d->file_key.c_str(), d->first, d->second);
    if (o.phi_edges.size() != ref.phi_edges.size() ||
        !std::equal(o.phi_edges.begin(), o.phi_edges.end(), ref.phi_edges.begin(), same))
      throw InputError(both +
                       " have different phi bins (/bins/phi_edges); filter the runs with the same bins "
                       "to pool them");
  }
}

}  // namespace cgd::fit
