#pragma once
// Synthetic filtered data for the fitter's tests: the C++ twin of tests/fit/make_synthetic_filtered.py
// (same truth, same noise model), in memory (FilteredFile) or written in the schema of
// docs/schema-filtered.md through core/h5.hpp.
#include <cmath>
#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "core/h5.hpp"
#include "fit/filtered_input.hpp"

namespace cgd::fit::testing {

/// Truth: h(phi) = 0.93 (1 - exp(-phi/0.07)) (1 - (phi/0.64)^4), a(phi) = 1.5 + 4 exp(-phi/0.12).
inline double truth_h(double phi) {
  return 0.93 * (1 - std::exp(-phi / 0.07)) * (1 - std::pow(phi / 0.64, 4));
}
inline double truth_a(double phi) {
  return 1.5 + 4 * std::exp(-phi / 0.12);
}

struct SyntheticSpec {
  int bins = 20;
  double phi_max = 0.5;
  std::vector<double> F{0.6, 0.4, 0.3, 0.2, 0.15, 0.1};  // L_char/width of the box widths
  bool whole_box = true;                                 // plus /whole_box at F = 0.063
  int runs = 2, snapshots = 100, block = 10;             // snapshots per run, per bootstrap block
  std::int64_t count = 400;                              // samples per snapshot and bin
  double noise = 0.1;                                    // sd of one snapshot's H
  std::uint64_t seed = 1;
  cgd::DragLaw micro_drag = cgd::DragLaw::Beetstra;
  double diameter_m = 75e-6;
  std::function<double(double phi, double F)> truth;  // H(phi, F); empty: truth_h/(1 + truth_a F)
  std::vector<double> noise_scale;                    // per width (F order; whole box last); empty: all 1
};

/// Per (run, snapshot, width, bin): micro = count * beta0, numerator = micro (1 - H_true - e), with
/// e = noise (0.6 xi_{s,b} + 0.8 eta_{s,w,b}) (correlated across widths: the same particles feed every
/// width), AR(1) in time with coefficient 0.5. H = 1 - sum N / sum M; the interval is H -/+ 1.96 x the
/// standard error of the block means (what a block bootstrap approximates).
inline FilteredFile make_synthetic(const SyntheticSpec& s) {
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> normal;
  FilteredFile f;
  f.path = "synthetic_" + std::to_string(s.seed) + ".h5";
  f.checksum = "0000000000000000";
  const double d = s.diameter_m, u_t = 0.2185, l_char = 4.02 * d;
  // |g| as a file without gravity_m_s2 gives it (write_filtered writes none: the older schema)
  f.physics = {s.micro_drag, u_t, l_char, d, 1500.0, 1.3, 1.8e-5, cgd::gravity_from_scales(u_t, l_char, d)};
  const int nb = s.bins, ns = s.runs * s.snapshots;
  for (int b = 0; b <= nb; ++b) f.phi_edges.push_back(s.phi_max * b / nb);
  for (int r = 0; r < s.runs; ++r) f.run_paths.push_back("synthetic/run_" + std::to_string(r));
  const int blocks_per_run = (s.snapshots + s.block - 1) / s.block;
  for (int r = 0; r < s.runs; ++r)
    for (int k = 0; k < s.snapshots; ++k) {
      f.snapshot_run.push_back(r);
      f.snapshot_block.push_back(r * blocks_per_run + k / s.block);
    }
  f.has_per_snapshot = true;
  auto ar1 = [&]() {  // (ns x nb) AR(1) noise, unit variance, independent runs
    std::vector<double> e(static_cast<std::size_t>(ns * nb));
    for (int r = 0; r < s.runs; ++r)
      for (int b = 0; b < nb; ++b) {
        double prev = normal(rng);
        for (int k = 0; k < s.snapshots; ++k) {
          prev = 0.5 * prev + std::sqrt(0.75) * normal(rng);
          e[static_cast<std::size_t>((r * s.snapshots + k) * nb + b)] = prev;
        }
      }
    return e;
  };
  const std::vector<double> common = ar1();
  std::vector<double> Fs = s.F;
  if (s.whole_box) Fs.push_back(0.063);
  const double beta0 = 1e4;
  for (std::size_t w = 0; w < Fs.size(); ++w) {
    WidthSeries ws;
    ws.whole_box = s.whole_box && w + 1 == Fs.size();
    ws.group = ws.whole_box ? "/whole_box" : "/width_" + std::to_string(w);
    ws.F = Fs[w];
    ws.width_m = l_char / Fs[w];
    const std::vector<double> own = ar1();
    ws.numerator.resize(static_cast<std::size_t>(ns * nb));
    ws.micro.assign(static_cast<std::size_t>(ns * nb), static_cast<double>(s.count) * beta0);
    ws.snapshot_count.assign(static_cast<std::size_t>(ns * nb), s.count);
    for (int b = 0; b < nb; ++b) {
      const double phi = 0.5 * (f.phi_edges[b] + f.phi_edges[b + 1]);
      const double H_true = s.truth ? s.truth(phi, Fs[w]) : truth_h(phi) / (1 + truth_a(phi) * Fs[w]);
      const double noise = s.noise * (s.noise_scale.empty() ? 1.0 : s.noise_scale.at(w));
      double num = 0, micro = 0;
      std::vector<double> block_num(static_cast<std::size_t>(s.runs * blocks_per_run)),
          block_micro(block_num.size());
      for (int k = 0; k < ns; ++k) {
        const std::size_t i = static_cast<std::size_t>(k * nb + b);
        const double e = noise * (0.6 * common[i] + 0.8 * own[i]);
        ws.numerator[i] = ws.micro[i] * (1 - H_true - e);
        num += ws.numerator[i];
        micro += ws.micro[i];
        block_num[static_cast<std::size_t>(f.snapshot_block[static_cast<std::size_t>(k)])] += ws.numerator[i];
        block_micro[static_cast<std::size_t>(f.snapshot_block[static_cast<std::size_t>(k)])] += ws.micro[i];
      }
      const double H = 1 - num / micro;
      double mean = 0, var = 0;
      const double nblk = static_cast<double>(block_num.size());
      for (std::size_t j = 0; j < block_num.size(); ++j) mean += (1 - block_num[j] / block_micro[j]) / nblk;
      for (std::size_t j = 0; j < block_num.size(); ++j)
        var += std::pow(1 - block_num[j] / block_micro[j] - mean, 2);
      const double se = std::sqrt(var / (nblk - 1) / nblk);
      ws.H.push_back(H);
      ws.H_low.push_back(H - 1.959963984540054 * se);
      ws.H_high.push_back(H + 1.959963984540054 * se);
      ws.phi_mean.push_back(phi);
      ws.count.push_back(s.count * ns);
    }
    f.widths.push_back(std::move(ws));
  }
  return f;
}

/// Write `f` as a filtered file (the datasets cgd-fit reads, plus the attributes the schema requires).
inline void write_filtered(const std::string& path, const FilteredFile& f, const std::string& scene_toml,
                           const std::string& format = "filtered") {
  h5::File h = h5::File::create(path, MPI_COMM_SELF);
  h.set_attr("/", "cgd_format", format);
  h.set_attr("/", "cgd_format_version", std::int64_t{1});
  h.set_attr("/", "scene", scene_toml);
  h.set_attr("/", "micro_drag", std::string(cgd::to_string(f.physics.micro_drag)));
  h.set_attr("/", "u_t_m_s", f.physics.u_t_m_s);
  h.set_attr("/", "l_char_m", f.physics.l_char_m);
  h.set_attr("/", "diameter_m", f.physics.diameter_m);
  h.set_attr("/", "particle_density_kg_m3", f.physics.particle_density_kg_m3);
  h.set_attr("/", "fluid_density_kg_m3", f.physics.fluid_density_kg_m3);
  h.set_attr("/", "fluid_viscosity_Pa_s", f.physics.fluid_viscosity_Pa_s);
  const std::uint64_t nb = f.bins(), ns = f.snapshots(), nr = f.runs();
  h.set_attr("/runs", "paths", f.run_paths);
  h.write_replicated("/runs/mean_solids_fraction", std::vector<double>(nr, 0.1), {nr});
  std::vector<std::int64_t> run_snapshots(nr, 0);
  for (std::int64_t r : f.snapshot_run) run_snapshots[static_cast<std::size_t>(r)] += 1;
  h.write_replicated("/runs/snapshot_count", run_snapshots, {nr});
  h.write_replicated("/snapshots/run_index", f.snapshot_run, {ns});
  h.write_replicated("/snapshots/block", f.snapshot_block, {ns});
  h.write_replicated("/bins/phi_edges", f.phi_edges, {nb + 1});
  for (const WidthSeries& w : f.widths) {
    h.set_attr(w.group, "F", w.F);
    h.set_attr(w.group, "width_m", w.width_m);
    h.set_attr(w.group, "kind", std::string(w.whole_box ? "whole_box" : "box"));
    h.write_replicated(w.group + "/H", w.H, {nb});
    h.write_replicated(w.group + "/H_low", w.H_low, {nb});
    h.write_replicated(w.group + "/H_high", w.H_high, {nb});
    h.write_replicated(w.group + "/phi_mean", w.phi_mean, {nb});
    h.write_replicated(w.group + "/count", w.count, {nb});
    if (f.has_per_snapshot) {
      h.write_replicated(w.group + "/per_snapshot/numerator", w.numerator, {ns, nb});
      h.write_replicated(w.group + "/per_snapshot/micro", w.micro, {ns, nb});
      h.write_replicated(w.group + "/per_snapshot/count", w.snapshot_count, {ns, nb});
    }
  }
  h.close();
}

}  // namespace cgd::fit::testing
