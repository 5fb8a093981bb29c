// Filtered files as the fitter sees them (see filtered_input.hpp): read and validated by their schema
// (core/schema/filtered.hpp, docs/schema-filtered.md), pooled and selected here.
#include "fit/filtered_input.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <sstream>

#include <gsl/gsl_statistics_double.h>
#include <gsl/gsl_sort.h>

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

FilteredFile pool_runs(const std::vector<FilteredFile>& files, std::uint64_t seed, int replicates) {
  if (files.empty()) throw InputError("--pool-runs: no filtered file given");
  if (files.size() == 1) return files.front();  // its H is already the pooled H of its runs
  check_same_physics(files);
  const FilteredFile& first = files.front();
  const std::size_t nb = first.bins();
  FilteredFile out;
  out.path = "pooled(";
  for (std::size_t i = 0; i < files.size(); ++i) out.path += (i ? " + " : "") + files[i].path;
  out.path += ")";
  out.scene_toml = first.scene_toml;
  out.physics = first.physics;
  out.phi_edges = first.phi_edges;
  out.has_per_snapshot = true;
  // the same series in the same order: group, F and cells across (what differs is named)
  auto describe = [](const std::vector<WidthSeries>& v) {
    std::string s;
    for (const WidthSeries& w : v) {
      std::ostringstream F;
      F << w.F;
      s += (s.empty() ? "" : ", ") + w.group + " (F = " + F.str() + ")";
    }
    return s.empty() ? std::string("none") : s;
  };
  auto same = [](const std::vector<WidthSeries>& x, const std::vector<WidthSeries>& y) {
    if (x.size() != y.size()) return false;
    for (std::size_t i = 0; i < x.size(); ++i)
      if (x[i].group != y[i].group || std::abs(x[i].F - y[i].F) > 1e-6 * std::abs(y[i].F) ||
          x[i].cells_across != y[i].cells_across)
        return false;
    return true;
  };
  // the runs one file after the other (run index offset by the runs before), each (run, block) a block of its own
  std::vector<std::int64_t> block_id;  // a global block of every snapshot row
  std::map<std::pair<std::int64_t, std::int64_t>, std::int64_t> ids;
  std::int64_t run_offset = 0;
  for (const FilteredFile& f : files) {
    if (!f.has_per_snapshot)
      throw InputError(f.path + ": --pool-runs needs the per-snapshot sums (/width_<k>/per_snapshot); filter the run "
                       "with this cgd-filter");
    for (const auto kind : {&FilteredFile::widths, &FilteredFile::grids})
      if (!same(f.*kind, first.*kind))
        throw InputError(f.path + " and " + first.path + ": --pool-runs pools files of the same widths and grids; " +
                         f.path + " has " + describe(f.*kind) + ", " + first.path + " " + describe(first.*kind) +
                         " (filter the runs with the same --widths and --grids)");
    out.run_paths.insert(out.run_paths.end(), f.run_paths.begin(), f.run_paths.end());
    std::int64_t runs_here = static_cast<std::int64_t>(f.runs());
    for (std::size_t k = 0; k < f.snapshots(); ++k) {
      const std::int64_t run = run_offset + f.snapshot_run[k];
      runs_here = std::max(runs_here, f.snapshot_run[k] + 1);
      out.snapshot_run.push_back(run);
      out.snapshot_block.push_back(f.snapshot_block[k]);
      const auto key = std::make_pair(run, f.snapshot_block[k]);
      const auto it = ids.emplace(key, static_cast<std::int64_t>(ids.size())).first;
      block_id.push_back(it->second);
    }
    run_offset += runs_here;
    out.pooled_paths.push_back(f.path);
    out.pooled_checksums.push_back(f.checksum);
  }
  std::vector<std::vector<std::int64_t>> blocks_of_run(static_cast<std::size_t>(run_offset));
  for (const auto& [key, id] : ids) blocks_of_run[static_cast<std::size_t>(key.first)].push_back(id);
  const std::size_t n_blocks = ids.size();
  // the bootstrap's replicates, drawn once: each draws within each run as many of its blocks as it has (the
  // multiplicity of every block), and the same draws serve every width and grid, as in cgd-filter
  std::mt19937_64 rng(seed);
  std::vector<std::vector<double>> mults(static_cast<std::size_t>(replicates), std::vector<double>(n_blocks, 0.0));
  for (std::vector<double>& mult : mults)
    for (const auto& blocks : blocks_of_run) {
      if (blocks.empty()) continue;
      std::uniform_int_distribution<std::size_t> pick(0, blocks.size() - 1);
      for (std::size_t j = 0; j < blocks.size(); ++j) mult[static_cast<std::size_t>(blocks[pick(rng)])] += 1.0;
    }
  // one series: the sums of every file's rows, its totals, its block sums and the bootstrap interval of H
  auto pooled = [&](auto series_of) {
    WidthSeries w = series_of(first);
    w.drift.reset();
    w.numerator.clear(), w.micro.clear(), w.snapshot_count.clear();
    std::vector<double> count(nb, 0.0), phi_sum(nb, 0.0);
    for (const FilteredFile& f : files) {
      const WidthSeries& s = series_of(f);
      w.numerator.insert(w.numerator.end(), s.numerator.begin(), s.numerator.end());
      w.micro.insert(w.micro.end(), s.micro.begin(), s.micro.end());
      w.snapshot_count.insert(w.snapshot_count.end(), s.snapshot_count.begin(), s.snapshot_count.end());
      for (std::size_t b = 0; b < nb; ++b)
        if (s.count[b] > 0 && std::isfinite(s.phi_mean[b]))
          count[b] += static_cast<double>(s.count[b]), phi_sum[b] += static_cast<double>(s.count[b]) * s.phi_mean[b];
    }
    const double nan = std::nan("");
    std::vector<double> block_num(n_blocks * nb, 0.0), block_mic(n_blocks * nb, 0.0), num(nb, 0.0), mic(nb, 0.0);
    for (std::size_t k = 0; k < block_id.size(); ++k)
      for (std::size_t b = 0; b < nb; ++b) {
        const auto blk = static_cast<std::size_t>(block_id[k]);
        block_num[blk * nb + b] += w.numerator[k * nb + b];
        block_mic[blk * nb + b] += w.micro[k * nb + b];
        num[b] += w.numerator[k * nb + b];
        mic[b] += w.micro[k * nb + b];
      }
    w.H.assign(nb, nan), w.H_low.assign(nb, nan), w.H_high.assign(nb, nan), w.phi_mean.assign(nb, nan);
    w.count.assign(nb, 0);
    for (std::size_t b = 0; b < nb; ++b) {
      w.count[b] = static_cast<std::int64_t>(std::llround(count[b]));
      if (count[b] > 0) w.phi_mean[b] = phi_sum[b] / count[b];
      if (count[b] > 0 && mic[b] != 0.0) w.H[b] = 1.0 - num[b] / mic[b];
    }
    std::vector<std::vector<double>> reps(nb);
    for (const std::vector<double>& mult : mults) {
      for (std::size_t b = 0; b < nb; ++b) {
        double n = 0, m = 0;
        for (std::size_t blk = 0; blk < n_blocks; ++blk)
          if (mult[blk] != 0.0) n += mult[blk] * block_num[blk * nb + b], m += mult[blk] * block_mic[blk * nb + b];
        if (m != 0.0) reps[b].push_back(1.0 - n / m);
      }
    }
    for (std::size_t b = 0; b < nb; ++b) {
      if (!std::isfinite(w.H[b]) || reps[b].size() < 2) continue;
      gsl_sort(reps[b].data(), 1, reps[b].size());  // percentile of type 7, as cgd-filter's (filter/statistics.hpp)
      w.H_low[b] = gsl_stats_quantile_from_sorted_data(reps[b].data(), 1, reps[b].size(), 0.025);
      w.H_high[b] = gsl_stats_quantile_from_sorted_data(reps[b].data(), 1, reps[b].size(), 0.975);
    }
    return w;
  };
  for (std::size_t i = 0; i < first.widths.size(); ++i)
    out.widths.push_back(pooled([i](const FilteredFile& f) -> const WidthSeries& { return f.widths[i]; }));
  for (std::size_t i = 0; i < first.grids.size(); ++i)
    out.grids.push_back(pooled([i](const FilteredFile& f) -> const WidthSeries& { return f.grids[i]; }));
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
