// run_filter: snapshots distributed over the ranks, per-snapshot sums reduced to rank 0, the block
// bootstrap, and the filtered file filled as a struct and written by rank 0 through its schema
// (core/schema/filtered.hpp, docs/schema-filtered.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <limits>
#include <optional>
#include <random>
#include <sstream>

#include "core/checksum.hpp"
#include "core/error.hpp"
#include "core/schema/filtered.hpp"
#include "core/timers.hpp"
#include "core/schema/series.hpp"
#include "core/schema/snapshot.hpp"
#include "core/scene.hpp"
#include "filter/filter.hpp"
#include "filter/statistics.hpp"

namespace cgd::filter {

namespace fs = std::filesystem;

namespace {

/// A duration for a progress line, rounded as a person reads it: "0.42 s", "12 s", "3.5 min", "1.3 h".
std::string rounded_duration(double s) {
  char buf[32];
  if (!(s >= 0) || !std::isfinite(s)) return "-";
  if (s < 10) std::snprintf(buf, sizeof buf, "%.1f s", s);
  else if (s < 120) std::snprintf(buf, sizeof buf, "%.0f s", s);
  else if (s < 7200) std::snprintf(buf, sizeof buf, "%.1f min", s / 60);
  else std::snprintf(buf, sizeof buf, "%.1f h", s / 3600);
  return buf;
}

constexpr int kSumFields = 5;  // count, numerator, micro, slip, phi
constexpr int kDriftFields = 6;  // the drift sums: count, numerator, denominator, magnitude, phi, slip (DriftSums)

/// An error on some ranks only must end the job on all of them (no rank left waiting in a
/// collective): every rank reports its status, and all throw the first failing rank's message.
void agree_on_errors(MPI_Comm comm, int status, const std::string& message) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  int first = status ? rank : 1 << 30;
  MPI_Allreduce(MPI_IN_PLACE, &first, 1, MPI_INT, MPI_MIN, comm);
  if (first == 1 << 30) return;
  int kind = status;
  int length = static_cast<int>(message.size());
  MPI_Bcast(&kind, 1, MPI_INT, first, comm);
  MPI_Bcast(&length, 1, MPI_INT, first, comm);
  std::string text(static_cast<std::size_t>(length), '\0');
  if (rank == first) text = message;
  MPI_Bcast(text.data(), length, MPI_CHAR, first, comm);
  if (kind == 2) throw InputError(text);
  throw RunError(text);
}

/// Runs `body` on every rank and ends the job on all of them with the first failing rank's error
/// (InputError stays InputError, anything else becomes a RunError).
template <class Body>
void on_all_ranks(MPI_Comm comm, Body&& body) {
  int status = 0;
  std::string message;
  try {
    body();
  } catch (const InputError& e) {
    status = 2;
    message = e.what();
  } catch (const std::exception& e) {
    status = 1;
    message = e.what();
  }
  agree_on_errors(comm, status, message);
}

struct Statistics {
  std::vector<double> tau, n_eff_run;
  std::vector<std::int64_t> block_len, block_of_row;
  // per width (incl. whole box) and bin
  std::vector<double> count, phi_mean, slip, drag, beta_bar, beta_micro, H, H_low, H_high, H_stderr, n_eff;
  std::vector<std::int64_t> count_int;
};

Statistics compute_statistics(const FilterPlan& plan, const FilterOptions& o, const std::vector<double>& sums) {
  const std::size_t n_widths = plan.columns(), n_bins = plan.bin_edges.size() - 1;
  const std::size_t whole_col = plan.whole_box_column();
  const std::size_t per_row = n_widths * n_bins * kSumFields;
  const std::size_t rows = sums.size() / per_row;
  auto at = [&](std::size_t row, std::size_t w, std::size_t b, int field) {
    return sums[row * per_row + (w * n_bins + b) * kSumFields + field];
  };
  Statistics st;
  // 1. per run: autocorrelation of the whole-box slip (the domain slip), block length, blocks
  std::vector<std::int64_t> run_of_block;
  std::size_t row = 0;
  for (std::size_t r = 0; r < plan.runs.size(); ++r) {
    const std::size_t n = plan.runs[r].files.size();
    std::vector<double> series;
    for (std::size_t k = 0; k < n; ++k) {
      double c = 0, s = 0;
      for (std::size_t b = 0; b < n_bins; ++b) {
        c += at(row + k, whole_col, b, 0);
        s += at(row + k, whole_col, b, 3);
      }
      series.push_back(c > 0 ? s / c : 0.0);
    }
    const double tau = integrated_autocorrelation_time(series);
    const std::int64_t b = block_length(tau, static_cast<std::int64_t>(n));
    st.tau.push_back(tau);
    st.block_len.push_back(b);
    st.n_eff_run.push_back(static_cast<double>(n) / (2.0 * tau));
    for (std::size_t k = 0; k < n; ++k) {
      if (k % static_cast<std::size_t>(b) == 0) run_of_block.push_back(static_cast<std::int64_t>(r));
      st.block_of_row.push_back(static_cast<std::int64_t>(run_of_block.size()) - 1);
    }
    row += n;
  }
  const std::size_t n_blocks = run_of_block.size();
  // 2. totals and block sums of numerator and micro per (width, bin)
  const std::size_t cells = n_widths * n_bins;
  std::vector<double> total(cells * kSumFields, 0.0), block_num(n_blocks * cells, 0.0), block_mic(n_blocks * cells, 0.0);
  std::vector<double> rows_with(cells * plan.runs.size(), 0.0);
  std::vector<std::size_t> run_of_row;
  for (std::size_t r = 0; r < plan.runs.size(); ++r) run_of_row.insert(run_of_row.end(), plan.runs[r].files.size(), r);
  for (std::size_t k = 0; k < rows; ++k)
    for (std::size_t c = 0; c < cells; ++c) {
      const double* s = &sums[k * per_row + c * kSumFields];
      for (int f = 0; f < kSumFields; ++f) total[c * kSumFields + f] += s[f];
      const auto blk = static_cast<std::size_t>(st.block_of_row[k]);
      block_num[blk * cells + c] += s[1];
      block_mic[blk * cells + c] += s[2];
      if (s[0] > 0) rows_with[c * plan.runs.size() + run_of_row[k]] += 1;
    }
  const double nan = std::nan("");
  auto resize = [&](std::vector<double>& v) { v.assign(cells, nan); };
  for (auto* v : {&st.count, &st.phi_mean, &st.slip, &st.drag, &st.beta_bar, &st.beta_micro, &st.H, &st.H_low,
                  &st.H_high, &st.H_stderr, &st.n_eff})
    resize(*v);
  st.count_int.assign(cells, 0);
  for (std::size_t c = 0; c < cells; ++c) {
    const double* t = &total[c * kSumFields];
    st.count[c] = t[0];
    st.count_int[c] = static_cast<std::int64_t>(std::llround(t[0]));
    if (!(t[0] > 0)) continue;
    st.phi_mean[c] = t[4] / t[0];
    st.slip[c] = t[3] / t[0];
    st.drag[c] = t[1] / t[0];
    st.beta_bar[c] = t[1] / t[3];
    st.beta_micro[c] = t[2] / t[3];
    st.H[c] = 1.0 - t[1] / t[2];
    double ne = 0;
    for (std::size_t r = 0; r < plan.runs.size(); ++r) ne += rows_with[c * plan.runs.size() + r] / (2.0 * st.tau[r]);
    st.n_eff[c] = ne;
  }
  // 3. block bootstrap: every replicate resamples, within each run, as many blocks as the run has,
  //    with replacement; the same resampled blocks serve every width and bin (one replicate = one
  //    alternative history of the runs).
  std::vector<std::vector<std::size_t>> blocks_of_run(plan.runs.size());
  for (std::size_t b = 0; b < n_blocks; ++b) blocks_of_run[static_cast<std::size_t>(run_of_block[b])].push_back(b);
  std::mt19937_64 rng(o.seed);
  const int R = o.bootstrap_replicates;
  std::vector<double> reps(static_cast<std::size_t>(R) * cells, nan);
  std::vector<double> mult(n_blocks), num(cells), mic(cells);
  for (int rep = 0; rep < R; ++rep) {
    std::fill(mult.begin(), mult.end(), 0.0);
    for (const auto& blocks : blocks_of_run) {
      std::uniform_int_distribution<std::size_t> pick(0, blocks.size() - 1);
      for (std::size_t k = 0; k < blocks.size(); ++k) mult[blocks[pick(rng)]] += 1;
    }
    std::fill(num.begin(), num.end(), 0.0);
    std::fill(mic.begin(), mic.end(), 0.0);
    for (std::size_t b = 0; b < n_blocks; ++b) {
      if (mult[b] == 0) continue;
      for (std::size_t c = 0; c < cells; ++c) {
        num[c] += mult[b] * block_num[b * cells + c];
        mic[c] += mult[b] * block_mic[b * cells + c];
      }
    }
    for (std::size_t c = 0; c < cells; ++c)
      if (mic[c] != 0) reps[c * static_cast<std::size_t>(R) + static_cast<std::size_t>(rep)] = 1.0 - num[c] / mic[c];
  }
  for (std::size_t c = 0; c < cells; ++c) {
    if (!(st.count[c] > 0)) continue;
    std::vector<double> v;
    for (int rep = 0; rep < R; ++rep) {
      const double x = reps[c * static_cast<std::size_t>(R) + static_cast<std::size_t>(rep)];
      if (!std::isnan(x)) v.push_back(x);
    }
    if (v.size() < 2) continue;
    double mean = 0, var = 0;
    for (double x : v) mean += x;
    mean /= static_cast<double>(v.size());
    for (double x : v) var += (x - mean) * (x - mean);
    st.H_stderr[c] = std::sqrt(var / static_cast<double>(v.size() - 1));
    const double alpha = 0.5 * (1.0 - 0.95);
    st.H_low[c] = percentile(v, alpha);
    st.H_high[c] = percentile(v, 1.0 - alpha);
  }
  return st;
}

/// The box width whose H matches a coarse grid's H_grid (docs/filter.md "Equivalent width").
struct EquivalentWidth {
  double width_m = NAN, rms = NAN;
  int bins = 0;
  bool at_bound = false;  // the best width is the narrowest or widest box filtered: a bound, not a match
};
constexpr const char* kEquivalentWidthMethod =
    "the box width Delta minimising sum_b (H_box(Delta, b) - H_grid(b))^2 / (se_grid(b)^2 + se_box(Delta, b)^2) over the "
    "bins with >= 100 samples at the grid and at every box width up to 4 grid cells, H_box(Delta, b) and se_box "
    "linear in Delta between those widths (pooled H of the runs; se = bootstrap standard deviation), Delta scanned on "
    "2001 points between the narrowest and the widest of them";

std::vector<EquivalentWidth> equivalent_widths(const FilterPlan& plan, const Statistics& st) {
  const std::size_t n_bins = plan.bin_edges.size() - 1, W_all = plan.widths_m.size(), whole = plan.whole_box_column();
  std::vector<EquivalentWidth> out(plan.grids.size());
  if (W_all < 2) return out;
  for (std::size_t g = 0; g < plan.grids.size(); ++g) {
    const std::size_t col = whole + 1 + g;
    // the widths up to 4 grid cells (sqrt(6) = 2.45 cells lies well inside): wider boxes hold fewer bins
    const double cell = plan.runs.front().coarse[g].grid.cell_size_m();
    std::size_t W = 0;
    while (W < W_all && (W < 2 || plan.widths_m[W] <= 4.0 * cell * (1 + 1e-9))) ++W;
    std::vector<std::size_t> bins;
    for (std::size_t b = 0; b < n_bins; ++b) {
      bool ok = st.count[col * n_bins + b] >= 100 && std::isfinite(st.H[col * n_bins + b]) &&
                std::isfinite(st.H_stderr[col * n_bins + b]);
      for (std::size_t w = 0; w < W && ok; ++w)
        ok = st.count[w * n_bins + b] >= 100 && std::isfinite(st.H[w * n_bins + b]) && std::isfinite(st.H_stderr[w * n_bins + b]);
      if (ok) bins.push_back(b);
    }
    EquivalentWidth& e = out[g];
    e.bins = static_cast<int>(bins.size());
    if (bins.empty()) continue;
    const double lo = plan.widths_m.front(), hi = plan.widths_m[W - 1];
    double best = std::numeric_limits<double>::infinity();
    int best_k = 0;
    const int steps = 2000;
    for (int k = 0; k <= steps; ++k) {
      const double delta = lo + (hi - lo) * k / steps;
      std::size_t w = 0;
      while (w + 2 < W && plan.widths_m[w + 1] < delta) ++w;
      const double t = std::clamp((delta - plan.widths_m[w]) / (plan.widths_m[w + 1] - plan.widths_m[w]), 0.0, 1.0);
      double chi2 = 0, sq = 0;
      for (std::size_t b : bins) {
        const double H0 = st.H[w * n_bins + b], H1 = st.H[(w + 1) * n_bins + b];
        const double s0 = st.H_stderr[w * n_bins + b], s1 = st.H_stderr[(w + 1) * n_bins + b];
        const double Hb = (1 - t) * H0 + t * H1, sb = (1 - t) * s0 + t * s1;
        const double r = Hb - st.H[col * n_bins + b], sg = st.H_stderr[col * n_bins + b];
        chi2 += r * r / std::max(sg * sg + sb * sb, 1e-30);
        sq += r * r;
      }
      if (chi2 < best) best = chi2, best_k = k, e.rms = std::sqrt(sq / static_cast<double>(bins.size()));
    }
    e.width_m = lo + (hi - lo) * best_k / steps;
    e.at_bound = best_k == 0 || best_k == steps;
  }
  return out;
}

/// The bootstrap's method, as the filtered file states it (attribute `bootstrap`).
constexpr const char* kBootstrapMethod =
    "non-overlapping block bootstrap over snapshots, blocks resampled within each run; block "
    "length max(1, round(2 tau_int)) snapshots, tau_int of the run's domain slip series "
    "(Sokal window, c = 5); percentile interval";

/// Column w (a width, the whole box or a grid) of a per-(width, bin) array.
template <class T>
std::vector<T> column(const std::vector<T>& v, std::size_t w, std::size_t n_bins) {
  return std::vector<T>(v.begin() + static_cast<std::ptrdiff_t>(w * n_bins),
                        v.begin() + static_cast<std::ptrdiff_t>((w + 1) * n_bins));
}

/// The per-snapshot sums of column w: (rows, n_bins) of each field of `sums`.
schema::FilteredGroup::PerSnapshot per_snapshot_sums(const std::vector<double>& sums, std::size_t w, std::size_t rows,
                                                     std::size_t n_widths, std::size_t n_bins) {
  const std::size_t per_row = n_widths * n_bins * kSumFields;
  auto field = [&](int k) {
    std::vector<double> v(rows * n_bins);
    for (std::size_t r = 0; r < rows; ++r)
      for (std::size_t b = 0; b < n_bins; ++b) v[r * n_bins + b] = sums[r * per_row + (w * n_bins + b) * kSumFields + k];
    return v;
  };
  schema::FilteredGroup::PerSnapshot p;  // fields: count, numerator, micro, slip, phi
  for (double c : field(0)) p.count.push_back(static_cast<std::int64_t>(std::llround(c)));
  p.numerator = field(1), p.micro = field(2), p.slip = field(3), p.phi = field(4);
  return p;
}

schema::FilteredGroup::Samples sample_columns(const std::vector<Sample>& samples) {
  schema::FilteredGroup::Samples s;
  for (const Sample& x : samples) {
    s.phi.push_back(x.phi);
    s.numerator.push_back(x.numerator);
    s.beta_micro.push_back(x.beta_micro);
    s.snapshot.push_back(x.snapshot);
    s.id.push_back(x.id);
    for (int d = 0; d < 3; ++d) s.slip.push_back(x.slip[d]), s.grad_p_filtered.push_back(x.grad_p_filtered[d]);
  }
  return s;
}

schema::FilteredGroup::Grid grid_attributes(const CoarseGrid& c, const EquivalentWidth& e, double diameter_m) {
  schema::FilteredGroup::Grid g;
  g.cells_across = static_cast<std::int64_t>(c.cells_across);
  g.cells.assign(c.grid.cells.begin(), c.grid.cells.end());
  g.dx_over_dp = c.dx_over_dp;
  g.cell_spacing_m.assign(c.grid.spacing_m.begin(), c.grid.spacing_m.end());
  g.cell_size_m = c.grid.cell_size_m();
  g.cell_size_over_dp = g.cell_size_m / diameter_m;
  g.void_fraction_floor = c.void_fraction_floor;
  g.equivalent_width_m = e.width_m;
  g.equivalent_width_over_dp = e.width_m / diameter_m;
  g.equivalent_width_over_grid_cell = e.width_m / g.cell_size_m;
  g.equivalent_width_bins = e.bins;
  g.equivalent_width_at_bound = e.at_bound;
  g.equivalent_width_rms = e.rms;
  g.equivalent_width_method = kEquivalentWidthMethod;
  return g;
}

/// The drift sums of every grid (`drift/` of /grids/<N>): totals over the snapshots in row order, H = numerator /
/// denominator, and its bootstrap standard deviation over the snapshot blocks of `st` (each replicate draws, within
/// each run, as many blocks as it has, with replacement; a seed of its own derived from --seed).
std::vector<schema::FilteredGroup::Drift> drift_groups(const FilterPlan& plan, const FilterOptions& o,
                                                       const std::vector<double>& drift, const Statistics& st,
                                                       const std::vector<std::int64_t>& drift_out_of_range) {
  const std::size_t n_grids = plan.grids.size(), n_bins = plan.bin_edges.size() - 1, n_slip = plan.slip_bins();
  const std::size_t cells = n_bins * n_slip, per_row = n_grids * cells * kDriftFields;
  const std::size_t rows = plan.snapshot_count();
  std::vector<schema::FilteredGroup::Drift> out(n_grids);
  if (n_slip == 0) return out;
  std::size_t n_blocks = 0;
  for (std::int64_t b : st.block_of_row) n_blocks = std::max(n_blocks, static_cast<std::size_t>(b) + 1);
  std::vector<std::vector<std::size_t>> blocks_of_run(plan.runs.size());
  {
    std::size_t row = 0;
    for (std::size_t r = 0; r < plan.runs.size(); ++r)
      for (std::size_t k = 0; k < plan.runs[r].files.size(); ++k, ++row) {
        const auto b = static_cast<std::size_t>(st.block_of_row[row]);
        if (blocks_of_run[r].empty() || blocks_of_run[r].back() != b) blocks_of_run[r].push_back(b);
      }
  }
  const double nan = std::nan("");
  for (std::size_t g = 0; g < n_grids; ++g) {
    schema::FilteredGroup::Drift& d = out[g];
    d.out_of_range = drift_out_of_range[g];
    std::vector<double> total(cells * kDriftFields, 0.0), block_num(n_blocks * cells, 0.0), block_den(n_blocks * cells, 0.0);
    schema::FilteredGroup::Drift::PerSnapshot ps;
    ps.count.assign(rows * cells, 0);
    ps.numerator.assign(rows * cells, 0.0);
    ps.denominator.assign(rows * cells, 0.0);
    for (std::size_t k = 0; k < rows; ++k) {
      const auto blk = static_cast<std::size_t>(st.block_of_row[k]);
      for (std::size_t c = 0; c < cells; ++c) {
        const double* x = &drift[k * per_row + (g * cells + c) * kDriftFields];
        for (int f = 0; f < kDriftFields; ++f) total[c * kDriftFields + f] += x[f];
        block_num[blk * cells + c] += x[1];
        block_den[blk * cells + c] += x[2];
        ps.count[k * cells + c] = static_cast<std::int64_t>(std::llround(x[0]));
        ps.numerator[k * cells + c] = x[1];
        ps.denominator[k * cells + c] = x[2];
      }
    }
    d.count.assign(cells, 0);
    d.numerator.assign(cells, 0.0);
    d.denominator.assign(cells, 0.0);
    d.magnitude.assign(cells, 0.0);
    for (auto* v : {&d.phi_mean, &d.slip_mean, &d.H, &d.H_stderr}) v->assign(cells, nan);
    for (std::size_t c = 0; c < cells; ++c) {
      const double* t = &total[c * kDriftFields];
      d.count[c] = static_cast<std::int64_t>(std::llround(t[0]));
      d.numerator[c] = t[1];
      d.denominator[c] = t[2];
      d.magnitude[c] = t[3];
      if (!(t[0] > 0)) continue;
      d.phi_mean[c] = t[4] / t[0];
      d.slip_mean[c] = t[5] / t[0];
      if (t[2] != 0.0) d.H[c] = t[1] / t[2];
    }
    // bootstrap standard deviation of H per bin (running mean and M2 over the replicates)
    std::mt19937_64 rng(o.seed ^ (0xd1f7ull + g));
    std::vector<double> mult(n_blocks), num(cells), den(cells), mean(cells, 0.0), m2(cells, 0.0), valid(cells, 0.0);
    for (int rep = 0; rep < o.bootstrap_replicates; ++rep) {
      std::fill(mult.begin(), mult.end(), 0.0);
      for (const auto& blocks : blocks_of_run) {
        if (blocks.empty()) continue;
        std::uniform_int_distribution<std::size_t> pick(0, blocks.size() - 1);
        for (std::size_t k = 0; k < blocks.size(); ++k) mult[blocks[pick(rng)]] += 1;
      }
      std::fill(num.begin(), num.end(), 0.0);
      std::fill(den.begin(), den.end(), 0.0);
      for (std::size_t b = 0; b < n_blocks; ++b) {
        if (mult[b] == 0) continue;
        for (std::size_t c = 0; c < cells; ++c) {
          num[c] += mult[b] * block_num[b * cells + c];
          den[c] += mult[b] * block_den[b * cells + c];
        }
      }
      for (std::size_t c = 0; c < cells; ++c) {
        if (den[c] == 0.0 || d.count[c] == 0) continue;
        const double h = num[c] / den[c];
        valid[c] += 1;
        const double delta = h - mean[c];
        mean[c] += delta / valid[c];
        m2[c] += delta * (h - mean[c]);
      }
    }
    for (std::size_t c = 0; c < cells; ++c)
      if (valid[c] > 1) d.H_stderr[c] = std::sqrt(m2[c] / (valid[c] - 1));
    if (o.drift_per_snapshot) d.per_snapshot = std::move(ps);  // the tables use the totals (docs/schema-filtered.md)
  }
  return out;
}

/// The filtered file (core/schema/filtered.hpp) of the plan's runs and their statistics, written by rank 0.
void write_filtered_file(const FilterPlan& plan, const FilterOptions& o, const std::vector<double>& sums,
                         const std::vector<std::int64_t>& out_of_range, const std::vector<std::vector<Sample>>& samples,
                         const Statistics& st, const std::vector<std::string>& checksums,
                         const std::vector<EquivalentWidth>& equivalent,
                         std::vector<schema::FilteredGroup::Drift> drift) {
  const RunPlan& r0 = plan.runs.front();
  const schema::RunPhysics& p = r0.physics;
  const std::size_t n_widths = plan.columns(), n_bins = plan.bin_edges.size() - 1, whole_col = plan.whole_box_column();
  schema::Filtered out;
  out.scene_toml = p.scene_toml;
  out.system = p.system();
  out.parcel_size = p.parcel_size;
  out.cell_size_m.assign(r0.grid.spacing_m.begin(), r0.grid.spacing_m.end());
  out.pressure_terms = p.pressure_gradient_force;
  out.bootstrap_replicates = o.bootstrap_replicates;
  out.bootstrap_seed = static_cast<std::int64_t>(o.seed);
  out.confidence = 0.95;
  out.bootstrap = kBootstrapMethod;
  for (std::size_t r = 0; r < plan.runs.size(); ++r) {
    const RunPlan& run = plan.runs[r];
    out.run_paths.push_back(run.path);
    out.run_mean_solids_fraction.push_back(run.physics.solids_fraction);
    out.run_snapshot_count.push_back(static_cast<std::int64_t>(run.files.size()));
    out.run_tau_int.push_back(st.tau[r]);
    out.run_block_length.push_back(st.block_len[r]);
    out.run_n_eff.push_back(st.n_eff_run[r]);
    for (std::size_t k = 0; k < run.files.size(); ++k) {
      out.snapshot_files.push_back(run.files[k]);
      out.snapshot_time_s.push_back(run.times_s[k]);
      out.snapshot_step.push_back(run.steps[k]);
      out.snapshot_run_index.push_back(static_cast<std::int64_t>(r));
    }
  }
  out.snapshot_checksums = checksums;
  out.snapshot_block = st.block_of_row;
  out.phi_edges = plan.bin_edges;
  out.slip_edges = plan.slip_edges;
  std::vector<double> centre(n_bins);
  for (std::size_t b = 0; b < n_bins; ++b) centre[b] = 0.5 * (plan.bin_edges[b] + plan.bin_edges[b + 1]);
  for (std::size_t w = 0; w < n_widths; ++w) {
    const bool whole = w == whole_col, grid = w > whole_col;
    const std::size_t gi = grid ? w - whole_col - 1 : 0;
    const double width = whole ? plan.whole_box_width_m : grid ? r0.coarse[gi].grid.cell_size_m() : plan.widths_m[w];
    schema::FilteredGroup g;
    g.kind = whole ? schema::FilterKind::WholeBox : grid ? schema::FilterKind::Grid : schema::FilterKind::Box;
    g.width_m = width;
    g.width_over_dp = width / p.diameter_m;
    g.width_over_cell = width / r0.grid.cell_size_m();
    g.F = p.l_char_m / width;
    g.out_of_range = out_of_range[w];
    if (grid) g.grid = grid_attributes(r0.coarse[gi], equivalent[gi], p.diameter_m);
    if (grid && plan.slip_bins() > 0) g.drift = std::move(drift[gi]);
    g.phi_center = centre;
    g.count = column(st.count_int, w, n_bins);
    g.phi_mean = column(st.phi_mean, w, n_bins);
    g.slip = column(st.slip, w, n_bins);
    g.slip_over_ut = g.slip;
    for (double& x : g.slip_over_ut) x /= p.u_t_m_s;
    g.drag = column(st.drag, w, n_bins);
    g.beta_bar = column(st.beta_bar, w, n_bins);
    g.beta_micro = column(st.beta_micro, w, n_bins);
    g.H = column(st.H, w, n_bins);
    g.H_low = column(st.H_low, w, n_bins);
    g.H_high = column(st.H_high, w, n_bins);
    g.H_stderr = column(st.H_stderr, w, n_bins);
    g.n_eff = column(st.n_eff, w, n_bins);
    g.per_snapshot = per_snapshot_sums(sums, w, plan.snapshot_count(), n_widths, n_bins);
    if (o.samples > 0) g.samples = sample_columns(samples[w]);
    out.groups.push_back(std::move(g));
  }
  // the first run's scene as this build loads it, for the common attributes and /params
  std::optional<Scene> scene;
  try {
    scene = load_scene_from_string(p.scene_toml, r0.path + "/scene");
  } catch (const std::exception& e) {
    // a run whose stored scene this build no longer reads (an older run): its text and the physical
    // system are still written, the /params of the common attributes are not; said, not swallowed
    std::cerr << "warning: " << e.what() << ": " << o.output_path
              << " gets the run's scene text without the common /params\n";
  }
  const fs::path parent = fs::path(o.output_path).parent_path();
  if (!parent.empty()) fs::create_directories(parent);
  schema::write_filtered(o.output_path, scene ? &*scene : nullptr, out);
}

}  // namespace

std::size_t run_filter(const FilterOptions& o, MPI_Comm comm) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const double t_start = wall_seconds();
  FilterPlan plan;
  on_all_ranks(comm, [&] { plan = plan_filter(o); });
  const std::size_t n_widths = plan.columns(), n_bins = plan.bin_edges.size() - 1;
  const std::size_t whole_col = plan.whole_box_column();
  const std::size_t rows = plan.snapshot_count();
  const double d = plan.runs.front().physics.diameter_m;
  if (rank == 0 && !o.quiet) {
    for (const std::string& w : plan.warnings) std::cerr << "warning: " << w << "\n";
    std::cerr << "cgd-filter: " << plan.runs.size() << " run(s), " << rows << " snapshot(s), " << size << " rank(s); widths (d_p):";
    for (double w : plan.widths_m) std::cerr << " " << w / d;
    std::cerr << " + whole box (" << plan.whole_box_width_m / d << "); " << n_bins << " bins of " << plan.bin_edges[1]
              << " in phi_bar\n";
  }
  // snapshot rows in run order; row k is filtered by rank k % size
  std::vector<std::pair<std::size_t, std::size_t>> row_of;  // (run, index in run)
  for (std::size_t r = 0; r < plan.runs.size(); ++r)
    for (std::size_t k = 0; k < plan.runs[r].files.size(); ++k) row_of.emplace_back(r, k);
  const std::size_t per_row = n_widths * n_bins * kSumFields;
  std::vector<double> sums(rows * per_row, 0.0);
  std::vector<std::int64_t> out_of_range(n_widths, 0);
  // the drift sums: per row, grid, phi bin and slip bin, kDriftFields each (a slot per snapshot: exact reduction)
  const std::size_t n_slip = plan.slip_bins();
  const std::size_t drift_per_row = plan.grids.size() * n_bins * n_slip * kDriftFields;
  std::vector<double> drift(rows * drift_per_row, 0.0);
  std::vector<std::int64_t> drift_out_of_range(plan.grids.size(), 0);
  std::vector<std::vector<Sample>> samples(n_widths);
  std::vector<std::string> checksums(rows);
  double read_s = 0, filter_s = 0;
  std::int64_t particle_widths = 0;
  on_all_ranks(comm, [&] {
    {
      std::size_t done = 0, mine = 0;
      for (std::size_t k = static_cast<std::size_t>(rank); k < rows; k += static_cast<std::size_t>(size)) ++mine;
      double last_print = wall_seconds();
      for (std::size_t k = static_cast<std::size_t>(rank); k < rows; k += static_cast<std::size_t>(size)) {
        const auto [r, i] = row_of[k];
        const double t0 = wall_seconds();
        const schema::Snapshot snap = schema::read_snapshot(plan.runs[r].files[i]);
        checksums[k] = file_checksum_fnv1a(plan.runs[r].files[i]);
        read_s += wall_seconds() - t0;
        SnapshotResult res = filter_snapshot(snap, plan, o, static_cast<std::int64_t>(k), r);
        filter_s += res.seconds;
        particle_widths += res.particles * static_cast<std::int64_t>(n_widths - 1);  // grids counted as widths
        for (std::size_t c = 0; c < n_widths * n_bins; ++c) {
          double* s = &sums[k * per_row + c * kSumFields];
          s[0] = res.sums[c].count;
          s[1] = res.sums[c].numerator;
          s[2] = res.sums[c].micro;
          s[3] = res.sums[c].slip;
          s[4] = res.sums[c].phi;
        }
        for (std::size_t c = 0; c < res.drift.size(); ++c) {
          double* x = &drift[k * drift_per_row + c * kDriftFields];
          const DriftSums& ds = res.drift[c];
          x[0] = ds.count, x[1] = ds.numerator, x[2] = ds.denominator, x[3] = ds.magnitude, x[4] = ds.phi, x[5] = ds.slip;
        }
        for (std::size_t g = 0; g < plan.grids.size(); ++g) drift_out_of_range[g] += res.drift_out_of_range[g];
        for (std::size_t w = 0; w < n_widths; ++w) {
          out_of_range[w] += res.out_of_range[w];
          samples[w].insert(samples[w].end(), res.samples[w].begin(), res.samples[w].end());
          if (o.samples > 0 && static_cast<std::int64_t>(samples[w].size()) > o.samples) {
            std::sort(samples[w].begin(), samples[w].end(), [](const Sample& a, const Sample& b) { return a.key < b.key; });
            samples[w].resize(static_cast<std::size_t>(o.samples));
          }
        }
        ++done;
        const double t = wall_seconds();
        if (rank == 0 && !o.quiet && (t - last_print > 2.0 || done == mine)) {
          const double per = (t - t_start) / static_cast<double>(done);
          std::cerr << "cgd-filter: " << done << "/" << mine << " snapshots of rank 0 (" << plan.runs[r].path << ", t = "
                    << plan.runs[r].times_s[i] << " s), " << rounded_duration(per) << " each, ETA "
                    << rounded_duration(per * static_cast<double>(mine - done)) << "\n";
          last_print = t;
        }
      }
    }
  });
  // Every snapshot's slot is filled by exactly one rank and zero elsewhere: the sum is exact.
  MPI_Allreduce(MPI_IN_PLACE, sums.data(), static_cast<int>(sums.size()), MPI_DOUBLE, MPI_SUM, comm);
  MPI_Allreduce(MPI_IN_PLACE, out_of_range.data(), static_cast<int>(n_widths), MPI_INT64_T, MPI_SUM, comm);
  if (!drift.empty()) {  // in pieces: the drift sums may exceed an int count for long pools
    const std::size_t piece = std::size_t{1} << 26;
    for (std::size_t at = 0; at < drift.size(); at += piece)
      MPI_Allreduce(MPI_IN_PLACE, drift.data() + at, static_cast<int>(std::min(piece, drift.size() - at)), MPI_DOUBLE,
                    MPI_SUM, comm);
  }
  if (!drift_out_of_range.empty())
    MPI_Allreduce(MPI_IN_PLACE, drift_out_of_range.data(), static_cast<int>(drift_out_of_range.size()), MPI_INT64_T,
                  MPI_SUM, comm);
  // checksums and samples to rank 0
  {
    std::string mine;
    for (std::size_t k = 0; k < rows; ++k) mine += checksums[k] + "\n";
    std::vector<char> all(mine.size() * static_cast<std::size_t>(size));
    MPI_Gather(mine.data(), static_cast<int>(mine.size()), MPI_CHAR, all.data(), static_cast<int>(mine.size()), MPI_CHAR, 0, comm);
    if (rank == 0) {
      for (int q = 0; q < size; ++q) {
        std::istringstream in(std::string(all.data() + mine.size() * static_cast<std::size_t>(q), mine.size()));
        std::string line;
        for (std::size_t k = 0; k < rows && std::getline(in, line); ++k)
          if (!line.empty()) checksums[k] = line;
      }
    }
  }
  if (o.samples > 0) {
    for (std::size_t w = 0; w < n_widths; ++w) {
      const int bytes = static_cast<int>(samples[w].size() * sizeof(Sample));
      std::vector<int> counts(static_cast<std::size_t>(size)), displs(static_cast<std::size_t>(size));
      MPI_Gather(&bytes, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm);
      int total = 0;
      for (int q = 0; q < size; ++q) {
        displs[static_cast<std::size_t>(q)] = total;
        total += counts[static_cast<std::size_t>(q)];
      }
      std::vector<Sample> all(rank == 0 ? static_cast<std::size_t>(total) / sizeof(Sample) : 0);
      MPI_Gatherv(samples[w].data(), bytes, MPI_BYTE, all.data(), counts.data(), displs.data(), MPI_BYTE, 0, comm);
      if (rank == 0) {
        std::sort(all.begin(), all.end(), [](const Sample& a, const Sample& b) { return a.key < b.key; });
        if (static_cast<std::int64_t>(all.size()) > o.samples) all.resize(static_cast<std::size_t>(o.samples));
        samples[w] = std::move(all);
      }
    }
  }
  double times[2] = {read_s, filter_s};
  MPI_Allreduce(MPI_IN_PLACE, times, 2, MPI_DOUBLE, MPI_SUM, comm);
  MPI_Allreduce(MPI_IN_PLACE, &particle_widths, 1, MPI_INT64_T, MPI_SUM, comm);
  on_all_ranks(comm, [&] {
    if (rank == 0) {
      try {
        const double t0 = wall_seconds();
        const Statistics st = compute_statistics(plan, o, sums);
        const std::vector<EquivalentWidth> equivalent = equivalent_widths(plan, st);
        write_filtered_file(plan, o, sums, out_of_range, samples, st, checksums, equivalent,
                            drift_groups(plan, o, drift, st, drift_out_of_range));
        if (!o.quiet) {
          const schema::RunPhysics& p = plan.runs.front().physics;
          std::cerr << "cgd-filter: wrote " << o.output_path << " in " << wall_seconds() - t_start << " s (reading "
                    << times[0] << " s, filtering " << times[1] << " s = "
                    << (times[1] > 0 ? static_cast<double>(particle_widths) / times[1] : 0.0)
                    << " particle-widths/s/core, statistics and writing " << wall_seconds() - t0 << " s)\n";
          for (std::size_t r = 0; r < plan.runs.size(); ++r)
            std::cerr << "  run " << plan.runs[r].path << ": " << plan.runs[r].files.size() << " snapshots, tau_int "
                      << st.tau[r] << " snapshots, block length " << st.block_len[r] << ", n_eff " << st.n_eff_run[r]
                      << "\n";
          // the whole box: the domain slip
          double c = 0, s = 0;
          for (std::size_t b = 0; b < n_bins; ++b) {
            c += st.count[whole_col * n_bins + b] > 0 ? st.count[whole_col * n_bins + b] : 0;
            s += st.count[whole_col * n_bins + b] > 0
                     ? st.slip[whole_col * n_bins + b] * st.count[whole_col * n_bins + b]
                     : 0;
          }
          std::cerr << "  whole box: mean slip " << (c > 0 ? s / c / p.u_t_m_s : 0.0) << " u_t\n";
          // the coarse grids: equivalent box widths and H_grid per bin (a report on stdout)
          for (std::size_t g = 0; g < plan.grids.size(); ++g) {
            const CoarseGrid& cg = plan.runs.front().coarse[g];
            const double h = cg.grid.cell_size_m();
            const EquivalentWidth& e = equivalent[g];
            std::cout << "grid " << plan.grids[g] << " across (" << cg.grid.cells[0] << " x " << cg.grid.cells[1] << " x "
                      << cg.grid.cells[2] << " cells of " << h / p.diameter_m << " d_p): equivalent box width ";
            if (e.bins > 0)
              std::cout << (e.at_bound ? "(at the end of the widths filtered) " : "") << e.width_m / p.diameter_m
                        << " d_p = " << e.width_m / h << " grid cells (TSC deposit+interpolate analytic sqrt(6) = "
                        << std::sqrt(6.0) << "), " << e.bins << " bins, rms H mismatch " << e.rms << "\n";
            else
              std::cout << "not determined (no bin with >= 100 samples at the grid and every width)\n";
            if (n_slip > 0) {  // the drift sums of this grid: how many (phi, slip) bins a drift table could use
              const std::size_t cells = n_bins * n_slip;
              std::vector<double> count(cells, 0.0);
              for (std::size_t k = 0; k < rows; ++k)
                for (std::size_t c = 0; c < cells; ++c) count[c] += drift[k * drift_per_row + (g * cells + c) * kDriftFields];
              const auto full = std::count_if(count.begin(), count.end(), [](double x) { return x >= 100; });
              std::cout << "  drift sums: " << full << " (phi_bar, cell slip) bins with >= 100 samples (slip bins of "
                        << plan.slip_edges[1] << " u_t up to " << plan.slip_edges.back() << " u_t), "
                        << drift_out_of_range[g] << " samples beyond them\n";
            }
            std::cout << "  phi_bar   count     H_grid   [95 % interval]\n";
            const std::size_t col = whole_col + 1 + g;
            for (std::size_t b = 0; b < n_bins; ++b) {
              const std::size_t i = col * n_bins + b;
              if (!(st.count[i] >= 100)) continue;
              char line[160];
              std::snprintf(line, sizeof line, "  %7.4f %7.0f %10.4f   [%.4f, %.4f]\n", st.phi_mean[i], st.count[i], st.H[i],
                            st.H_low[i], st.H_high[i]);
              std::cout << line;
            }
          }
        }
      } catch (const InputError&) {
        throw;
      } catch (const std::exception& e) {
        throw RunError(std::string("writing ") + o.output_path + ": " + e.what());
      }
    }
  });
  return rows;
}

}  // namespace cgd::filter
