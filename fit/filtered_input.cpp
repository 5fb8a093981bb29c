// Reading filtered files for the fitter (see filtered_input.hpp, docs/schema-filtered.md).
#include "fit/filtered_input.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

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
  schema::check_format(f, schema::kFiltered);
  FilteredFile out;
  out.path = path;
  need_attr("/", "scene");
  out.physics = read_physical_system(f, "micro_drag", "filtered file");
  out.scene_toml = f.attr_string("/", "scene");
  const PhysicalSystem& p = out.physics;
  if (!(p.l_char_m > 0)) throw InputError(path + ": l_char_m = " + number(p.l_char_m) + ": must be > 0");

  using schema::Finite;
  using schema::kAnyExtent;
  out.phi_edges = schema::read_doubles(f, "/bins/phi_edges", {kAnyExtent}, Finite::Everywhere);
  const std::size_t nb = out.bins();
  if (nb < 1 || std::adjacent_find(out.phi_edges.begin(), out.phi_edges.end(), std::greater_equal<>()) !=
                    out.phi_edges.end())
    throw InputError(path + ": dataset '/bins/phi_edges' must hold at least two increasing edges");

  // /runs and /snapshots
  out.run_paths =
      f.has_attr("/runs", "paths") ? f.attr_strings("/runs", "paths") : std::vector<std::string>{};
  const std::size_t n_runs =
      schema::read_doubles(f, "/runs/mean_solids_fraction", {kAnyExtent}, Finite::Everywhere).size();
  if (out.run_paths.size() != n_runs) out.run_paths.resize(n_runs, path);
  const std::string per_run = "one row per run, the length of /runs/mean_solids_fraction";
  const std::vector<std::int64_t> run_snapshots = schema::read_ints(f, "/runs/snapshot_count", {n_runs}, per_run);
  out.snapshot_run = schema::read_ints(f, "/snapshots/run_index", {kAnyExtent});
  const std::size_t ns = out.snapshot_run.size();
  const std::string per_snapshot = "one row per snapshot, the length of /snapshots/run_index";
  out.snapshot_block = schema::read_ints(f, "/snapshots/block", {ns}, per_snapshot);
  std::int64_t listed = 0;
  for (std::int64_t c : run_snapshots) listed += c;
  if (listed != static_cast<std::int64_t>(ns))
    throw InputError(path + ": dataset '/runs/snapshot_count' sums to " + std::to_string(listed) +
                     " snapshots, expected " + std::to_string(ns) + " (the rows of /snapshots/run_index)");
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
    w.F = schema::finite_attr(f, g, "F");
    if (f.has_attr(g, "width_m")) w.width_m = schema::finite_attr(f, g, "width_m");
    if (f.has_attr(g, "width_over_cell")) w.width_over_cell = schema::finite_attr(f, g, "width_over_cell");
    w.whole_box = g == "/whole_box";
    w.grid = gi >= n_box_groups;
    if (w.grid) {
      for (const char* key : {"cells_across", "cell_size_over_dp"}) need_attr(g, key);
      w.cells_across = f.attr_int(g, "cells_across");
      w.cell_size_over_dp = schema::finite_attr(f, g, "cell_size_over_dp");
    }
    if (!(w.F > 0)) throw InputError(path + ": " + g + " attribute F = " + number(w.F) + ": must be > 0");
    // per-bin datasets: n_bins long; the float ones NaN only in empty bins (H_low, H_high: also where the
    // bootstrap could not form an interval)
    const std::string per_bin = "n_bins = len(/bins/phi_edges) - 1 = " + std::to_string(nb);
    w.count = schema::read_ints(f, g + "/count", {nb}, per_bin);
    for (std::size_t b = 0; b < nb; ++b)
      if (w.count[b] < 0)
        throw InputError(path + ": dataset '" + g + "/count' holds " + std::to_string(w.count[b]) + " in bin " +
                         std::to_string(b) + ", expected counts >= 0");
    auto per_bin_values = [&](const char* name, bool finite_where_counted) {
      std::vector<double> v = schema::read_doubles(f, g + "/" + name, {nb}, Finite::Not, per_bin);
      if (finite_where_counted) schema::require_finite_where_counted(path, g + "/" + name, v, w.count);
      return v;
    };
    w.H = per_bin_values("H", true);
    w.H_low = per_bin_values("H_low", false);
    w.H_high = per_bin_values("H_high", false);
    w.phi_mean = per_bin_values("phi_mean", true);
    for (const char* name : {"slip", "drag"})
      if (f.exists(g + "/" + name)) per_bin_values(name, true);
    if (out.has_per_snapshot) {
      const std::string shape = "(n_snapshots, n_bins) = (" + std::to_string(ns) + ", " + std::to_string(nb) + ")";
      w.numerator = schema::read_doubles(f, g + "/per_snapshot/numerator", {ns, nb}, Finite::Everywhere, shape);
      w.micro = schema::read_doubles(f, g + "/per_snapshot/micro", {ns, nb}, Finite::Everywhere, shape);
      w.snapshot_count = schema::read_ints(f, g + "/per_snapshot/count", {ns, nb}, shape);
      for (std::size_t b = 0; b < nb; ++b) {
        std::int64_t sum = 0;
        for (std::size_t k = 0; k < ns; ++k) sum += w.snapshot_count[k * nb + b];
        if (sum != w.count[b])
          throw InputError(path + ": dataset '" + g + "/per_snapshot/count' sums to " + std::to_string(sum) +
                           " samples in bin " + std::to_string(b) + ", expected " + std::to_string(w.count[b]) +
                           " (" + g + "/count)");
      }
    }
    (w.grid ? out.grids : out.widths).push_back(std::move(w));
  }
  f.close();
  out.checksum = file_checksum_fnv1a(path);
  return out;
}

std::vector<FilteredFile> select_operator(const std::vector<FilteredFile>& files, CalibrationOperator op) {
  if (op == CalibrationOperator::Box) return files;
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
