// Filtered files as the fitter sees them (see filtered_input.hpp): read and validated by their schema
// (core/schema/filtered.hpp, docs/schema-filtered.md), pooled and selected here.
#include "fit/filtered_input.hpp"

#include <algorithm>
#include <cmath>

#include "core/checksum.hpp"
#include "core/drag.hpp"
#include "core/error.hpp"
#include "core/schema/filtered.hpp"

namespace cgd::fit {

namespace {

/// The fitter's view of one group of the file.
WidthSeries width_series(const schema::FilteredGroup& g, const std::string& path) {
  WidthSeries w;
  w.group = path;
  w.F = g.F;
  w.width_m = std::isnan(g.width_m) ? 0.0 : g.width_m;
  w.width_over_cell = g.width_over_cell;
  w.whole_box = g.kind == schema::FilterKind::WholeBox;
  w.grid = g.kind == schema::FilterKind::Grid;
  if (g.grid) {
    w.cells_across = g.grid->cells_across;
    w.cell_size_over_dp = g.grid->cell_size_over_dp;
  }
  w.H = g.H, w.H_low = g.H_low, w.H_high = g.H_high, w.phi_mean = g.phi_mean, w.count = g.count;
  if (g.per_snapshot) {
    w.numerator = g.per_snapshot->numerator;
    w.micro = g.per_snapshot->micro;
    w.snapshot_count = g.per_snapshot->count;
  }
  if (g.drift) w.drift = WidthSeries::Drift{g.drift->count, g.drift->numerator, g.drift->denominator, g.drift->magnitude};
  return w;
}

}  // namespace

FilteredFile read_filtered_file(const std::string& path) {
  const schema::Filtered s = schema::read_filtered(path);  // validated there
  FilteredFile out;
  out.path = path;
  out.scene_toml = s.scene_toml;
  out.physics = s.system;
  out.phi_edges = s.phi_edges;
  out.slip_edges = s.slip_edges;
  out.run_paths = s.run_paths;
  out.snapshot_run = s.snapshot_run_index;
  out.snapshot_block = s.snapshot_block;
  out.has_per_snapshot = !s.groups.empty() && s.groups.front().per_snapshot.has_value();
  const std::vector<std::string> paths = schema::group_paths(s);
  for (std::size_t i = 0; i < s.groups.size(); ++i)
    (s.groups[i].kind == schema::FilterKind::Grid ? out.grids : out.widths).push_back(width_series(s.groups[i], paths[i]));
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
