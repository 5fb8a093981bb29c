// The filtered file's write and validating read (core/schema/filtered.hpp, docs/schema-filtered.md).
#include "core/schema/filtered.hpp"

#include <algorithm>
#include <cstdio>
#include <functional>

#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/schema/common.hpp"
#include "core/schema/calibration.hpp"
#include "core/schema/check.hpp"
#include "core/version.hpp"

namespace cgd::schema {

namespace {

using Group = FilteredGroup;

// root
constexpr const char* kScene = "scene";
constexpr const char* kParcelSize = "parcel_size";
constexpr const char* kCellSize = "cell_size_m";
constexpr const char* kPressureTerms = "pressure_terms";
constexpr const char* kHDefinition = "H_definition";
constexpr const char* kBootstrapReplicates = "bootstrap_replicates";
constexpr const char* kBootstrapSeed = "bootstrap_seed";
constexpr const char* kConfidence = "confidence";
constexpr const char* kBootstrap = "bootstrap";
constexpr const char* kHDefinitionText =
    "H = 1 - sum_i N_i / sum_i beta_micro(phi_bar_i, |u_slip_bar_i|) u_slip_bar_i,y over a bin; "
    "N_i = [-grad p_i + grad p_bar_i + beta_p,i (u_i - v_i)]_y; u_slip_bar_i = "
    "filter(eps u)/filter(eps) at x_i - v_i; box filter of edge width_m centred on the particle";
// groups
constexpr const char* kRuns = "/runs";
constexpr const char* kSnapshots = "/snapshots";
constexpr const char* kBins = "/bins";
constexpr const char* kPhiEdges = "/bins/phi_edges";
constexpr const char* kSlipEdges = "/bins/slip_edges";
constexpr const char* kDriftDefinition =
    "per grid and (phi bin, s_hat bin): vbar_c = sum_i w_ic v_i / sum_i w_ic (TSC deposit of the particle velocities "
    "on the grid; u_C where nothing is deposited), vbar_i = sum_c w_ic vbar_c, cell slip s~_i = u~_i - vbar_i, "
    "s_hat_i = |s~_i| / u_t; numerator = sum_i (M_i - N_i), denominator = sum_i beta_micro,i s~_i,y, magnitude = "
    "sum_i beta_micro,i |s~_i| (M_i, N_i, beta_micro,i of the grid's H); H = numerator / denominator: the drift "
    "closure F_i = V beta_micro [(u~_i - v_i) - H s~_i] reproduces the bin's total drag";
constexpr const char* kGrids = "/grids";
constexpr const char* kWholeBox = "/whole_box";
constexpr const char* kWidthPrefix = "/width_";
constexpr const char* kChecksumKind = "FNV-1a 64-bit of the file's bytes, hex";
constexpr const char* kGridsDefinition =
    "per coarse grid (the grid a coarse run with cells_across cells along x builds): phi = TSC "
    "deposit of the particles' volume on the coarse cells with the coupler's conservative floor; "
    "u = box average over the coarse cell of eps u_c / box average of eps (Favre; u_c the "
    "resolved cell-centred velocity); p = box average over the cell; grad p = central "
    "differences of the cell values; phi, u, grad p TSC-interpolated to each particle";

/// A per-bin float dataset of a width group: required or not, finite in every bin with samples or not.
struct PerBin {
  const char* name;
  std::vector<double> Group::*member;
  bool required;
  bool finite_where_counted;
};
// in the order the writer creates them (count is written after phi_center)
constexpr PerBin kPerBin[] = {
    {"phi_center", &Group::phi_center, false, false}, {"phi_mean", &Group::phi_mean, true, true},
    {"slip", &Group::slip, false, true},              {"slip_over_ut", &Group::slip_over_ut, false, false},
    {"drag", &Group::drag, false, true},              {"beta_bar", &Group::beta_bar, false, false},
    {"beta_micro", &Group::beta_micro, false, false}, {"H", &Group::H, true, true},
    {"H_low", &Group::H_low, true, false},            {"H_high", &Group::H_high, true, false},
    {"H_stderr", &Group::H_stderr, false, false},     {"n_eff", &Group::n_eff, false, false},
};

/// A float attribute of a group that may be absent (NaN then).
struct GroupNumber {
  const char* name;
  double Group::*member;
};
constexpr GroupNumber kGroupNumbers[] = {
    {"width_m", &Group::width_m}, {"width_over_dp", &Group::width_over_dp}, {"width_over_cell", &Group::width_over_cell}};

using Grid = Group::Grid;
struct GridNumber {
  const char* name;
  double Grid::*member;
};
constexpr GridNumber kGridNumbers[] = {
    {"dx_over_dp", &Grid::dx_over_dp},
    {"cell_size_m", &Grid::cell_size_m},
    {"void_fraction_floor", &Grid::void_fraction_floor},
};
// NaN when no bin qualifies (docs/filter.md "Equivalent width"): not checked finite
constexpr GridNumber kEquivalentNumbers[] = {
    {"equivalent_width_m", &Grid::equivalent_width_m},
    {"equivalent_width_over_dp", &Grid::equivalent_width_over_dp},
    {"equivalent_width_over_grid_cell", &Grid::equivalent_width_over_grid_cell},
};

using PerSnapshot = Group::PerSnapshot;
struct SnapshotSums {
  const char* name;
  std::vector<double> PerSnapshot::*member;
  bool required;
};
constexpr SnapshotSums kSnapshotSums[] = {{"numerator", &PerSnapshot::numerator, true},
                                          {"micro", &PerSnapshot::micro, true},
                                          {"slip", &PerSnapshot::slip, false},
                                          {"phi", &PerSnapshot::phi, false}};

using Drift = Group::Drift;
struct DriftNumber {
  const char* name;
  std::vector<double> Drift::*member;
  Finite finite;
};
// (n_bins, n_slip) float datasets of drift/: the sums finite everywhere, the ratios NaN where empty
constexpr DriftNumber kDriftNumbers[] = {{"numerator", &Drift::numerator, Finite::Everywhere},
                                         {"denominator", &Drift::denominator, Finite::Everywhere},
                                         {"magnitude", &Drift::magnitude, Finite::Everywhere},
                                         {"phi_mean", &Drift::phi_mean, Finite::Not},
                                         {"slip_mean", &Drift::slip_mean, Finite::Not},
                                         {"H", &Drift::H, Finite::Not},
                                         {"H_stderr", &Drift::H_stderr, Finite::Not}};

using Samples = Group::Samples;
struct SampleColumn {
  const char* name;
  std::vector<double> Samples::*member;
  std::uint64_t width;
};
constexpr SampleColumn kSampleColumns[] = {{"phi", &Samples::phi, 1},
                                           {"slip", &Samples::slip, 3},
                                           {"grad_p_filtered", &Samples::grad_p_filtered, 3},
                                           {"numerator", &Samples::numerator, 1},
                                           {"beta_micro", &Samples::beta_micro, 1}};

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

// ---- write --------------------------------------------------------------------------------------

void write_vector(h5::File& f, const std::string& name, const std::vector<double>& v) {
  f.write_replicated(name, v, {v.size()});
}
void write_vector(h5::File& f, const std::string& name, const std::vector<std::int64_t>& v) {
  f.write_replicated(name, v, {v.size()});
}

void write_root(h5::File& f, const Scene* scene, const Filtered& s) {
  if (scene) {
    write_common(f, kFiltered, *scene);
  } else {
    f.set_attr("/", "cgd_format", std::string(kFiltered.name));
    f.set_attr("/", "cgd_format_version", kFiltered.version);
    f.set_attr("/", "code_version", std::string(code_version()));
    f.set_attr("/", kScene, s.scene_toml);
  }
  write_physical_system(f, s.system, names::kMicroLawAttribute);
  f.set_attr("/", kParcelSize, s.parcel_size);
  f.set_attr("/", kCellSize, s.cell_size_m);
  f.set_attr("/", kPressureTerms, std::int64_t{s.pressure_terms.value_or(true) ? 1 : 0});
  f.set_attr("/", kHDefinition, std::string(kHDefinitionText));
  f.set_attr("/", kBootstrapReplicates, s.bootstrap_replicates);
  f.set_attr("/", kBootstrapSeed, s.bootstrap_seed);
  f.set_attr("/", kConfidence, s.confidence);
  f.set_attr("/", kBootstrap, s.bootstrap);
}

void write_runs_and_snapshots(h5::File& f, const Filtered& s) {
  f.create_group(kRuns);
  f.set_attr(kRuns, "paths", s.run_paths);
  write_vector(f, "/runs/mean_solids_fraction", s.run_mean_solids_fraction);
  write_vector(f, "/runs/snapshot_count", s.run_snapshot_count);
  write_vector(f, "/runs/block_length", s.run_block_length);
  write_vector(f, "/runs/tau_int", s.run_tau_int);
  write_vector(f, "/runs/n_eff", s.run_n_eff);
  f.create_group(kSnapshots);
  f.set_attr(kSnapshots, "files", s.snapshot_files);
  f.set_attr(kSnapshots, "checksums", s.snapshot_checksums);
  f.set_attr(kSnapshots, "checksum_kind", std::string(kChecksumKind));
  write_vector(f, "/snapshots/run_index", s.snapshot_run_index);
  write_vector(f, "/snapshots/time_s", s.snapshot_time_s);
  write_vector(f, "/snapshots/step", s.snapshot_step);
  write_vector(f, "/snapshots/block", s.snapshot_block);
  f.create_group(kBins);
  write_vector(f, kPhiEdges, s.phi_edges);
  if (!s.slip_edges.empty()) {
    write_vector(f, kSlipEdges, s.slip_edges);
    f.set_attr(kBins, "slip_unit", std::string("u_t"));
    f.set_attr(kBins, "drift_definition", std::string(kDriftDefinition));
  }
  f.set_attr(kBins, "width", s.phi_edges.size() > 1 ? s.phi_edges[1] - s.phi_edges[0] : 0.0);
}

void write_grid_attributes(h5::File& f, const std::string& g, const Grid& c) {
  f.set_attr(g, "cells_across", c.cells_across);
  f.set_attr(g, "cells", c.cells);
  f.set_attr(g, "dx_over_dp", c.dx_over_dp);
  f.set_attr(g, "cell_spacing_m", c.cell_spacing_m);
  f.set_attr(g, "cell_size_m", c.cell_size_m);
  f.set_attr(g, "cell_size_over_dp", c.cell_size_over_dp);
  f.set_attr(g, "kernel", std::string("tsc"));
  f.set_attr(g, "operator", std::string(to_string(CalibrationOperator::Grid)));
  f.set_attr(g, "void_fraction_floor", c.void_fraction_floor);
  for (const auto& n : kEquivalentNumbers) f.set_attr(g, n.name, c.*n.member);
  f.set_attr(g, "equivalent_width_bins", c.equivalent_width_bins);
  f.set_attr(g, "equivalent_width_at_bound", std::int64_t{c.equivalent_width_at_bound ? 1 : 0});
  f.set_attr(g, "equivalent_width_rms", c.equivalent_width_rms);
  f.set_attr(g, "equivalent_width_analytic_over_grid_cell", std::sqrt(6.0));
  f.set_attr(g, "equivalent_width_method", c.equivalent_width_method);
}

// The tables of a width or grid group, compressed (h5::Storage): the per-snapshot and drift sums are mostly
// zeros (empty bins), 4.2 MB uncompressed for one half-box run with the 4-cell grid's drift sums.
constexpr h5::Storage kPacked = h5::Storage::Compressed;

void write_drift(h5::File& f, const std::string& g, const Drift& d, std::uint64_t n_snapshots, std::uint64_t nb,
                 std::uint64_t n_slip) {
  const std::string dg = g + "/drift";
  f.create_group(dg);
  f.set_attr(dg, "out_of_range", d.out_of_range);
  f.write_replicated(dg + "/count", d.count, {nb, n_slip}, kPacked);
  for (const DriftNumber& n : kDriftNumbers)
    f.write_replicated(dg + "/" + n.name, d.*n.member, {nb, n_slip}, kPacked);
  if (d.per_snapshot) {
    const std::string ps = dg + "/per_snapshot";
    f.create_group(ps);
    f.write_replicated(ps + "/count", d.per_snapshot->count, {n_snapshots, nb, n_slip}, kPacked);
    f.write_replicated(ps + "/numerator", d.per_snapshot->numerator, {n_snapshots, nb, n_slip}, kPacked);
    f.write_replicated(ps + "/denominator", d.per_snapshot->denominator, {n_snapshots, nb, n_slip}, kPacked);
  }
}

void write_group(h5::File& f, const std::string& g, const Group& w, std::uint64_t n_snapshots, std::uint64_t nb,
                 std::uint64_t n_slip) {
  f.create_group(g);
  f.set_attr(g, "kind", std::string(to_string(w.kind)));
  for (const auto& n : kGroupNumbers) f.set_attr(g, n.name, w.*n.member);
  f.set_attr(g, "F", w.F);
  f.set_attr(g, "out_of_range", w.out_of_range);
  if (w.grid) write_grid_attributes(f, g, *w.grid);
  for (const PerBin& b : kPerBin) {
    const std::vector<double>& v = w.*b.member;
    if (b.required || !v.empty()) f.write_replicated(g + "/" + b.name, v, {nb}, kPacked);
    if (b.member == &Group::phi_center) f.write_replicated(g + "/count", w.count, {nb}, kPacked);
  }
  if (w.per_snapshot) {
    const std::string ps = g + "/per_snapshot";
    f.create_group(ps);
    f.write_replicated(ps + "/count", w.per_snapshot->count, {n_snapshots, nb}, kPacked);
    for (const SnapshotSums& s : kSnapshotSums)
      if (s.required || !((*w.per_snapshot).*s.member).empty())
        f.write_replicated(ps + "/" + s.name, (*w.per_snapshot).*s.member, {n_snapshots, nb}, kPacked);
  }
  if (w.drift) write_drift(f, g, *w.drift, n_snapshots, nb, n_slip);
  if (w.samples) {
    const Samples& s = *w.samples;
    const std::string sg = g + "/samples";
    const std::uint64_t n = s.phi.size();
    f.create_group(sg);
    for (const SampleColumn& c : kSampleColumns) {
      if (c.member == &Samples::beta_micro) {  // numerator, beta_micro, then the integer columns
        f.write_replicated(sg + "/" + c.name, s.*c.member, {n}, kPacked);
        f.write_replicated(sg + "/snapshot", s.snapshot, {n}, kPacked);
        f.write_replicated(sg + "/id", s.id, {n}, kPacked);
        continue;
      }
      f.write_replicated(sg + "/" + c.name, s.*c.member,
                         c.width == 1 ? std::vector<std::uint64_t>{n} : std::vector<std::uint64_t>{n, c.width},
                         kPacked);
    }
  }
}

// ---- read ---------------------------------------------------------------------------------------

double optional_finite(const h5::File& f, const std::string& object, const char* name) {
  return f.has_attr(object, name) ? finite_attr(f, object, name) : NAN;
}

std::vector<double> optional_doubles(const h5::File& f, const std::string& name, const std::vector<std::uint64_t>& shape,
                                     Finite finite, const std::string& why) {
  return f.exists(name) ? read_doubles(f, name, shape, finite, why) : std::vector<double>{};
}
std::vector<std::int64_t> optional_ints(const h5::File& f, const std::string& name,
                                        const std::vector<std::uint64_t>& shape, const std::string& why) {
  return f.exists(name) ? read_ints(f, name, shape, why) : std::vector<std::int64_t>{};
}

void require_kind(const h5::File& f, const std::string& g, FilterKind expected) {
  if (!f.has_attr(g, "kind")) return;  // hand-made files may leave it out: the path says it
  const std::string kind = f.attr_string(g, "kind");
  if (kind != to_string(expected))
    throw InputError(f.path() + ": attribute 'kind' of '" + g + "' is \"" + kind + "\", expected \"" +
                     to_string(expected) + "\" (the group's path)");
}

/// The spelling that changed with version 2 (docs/schema-filtered.md "Versions"): version 2 spells the grids'
/// `operator` "grid", as the groups' `kind`, cgd-fit --operator and the drag model file do; version 1 (the files
/// written before) spelled it "tsc-deposit-interpolate". The one upgrade path: the reader of a version-1 file
/// takes that spelling, and only a version-1 file.
constexpr const char* kVersion1GridOperator = "tsc-deposit-interpolate";
const char* upgrade_version1(std::int64_t version) {
  return version == 1 ? kVersion1GridOperator : to_string(CalibrationOperator::Grid);
}

void require_grid_operator(const h5::File& f, const std::string& object, std::int64_t version) {
  if (!f.has_attr(object, "operator")) return;
  const std::string text = f.attr_string(object, "operator");
  const char* expected = upgrade_version1(version);
  if (text != expected)
    throw InputError(f.path() + ": attribute 'operator' of '" + object + "' is \"" + text + "\", expected \"" +
                     expected + "\" (cgd_format_version " + std::to_string(version) + ")");
}

void read_root(const h5::File& f, Filtered& s) {
  if (!f.has_attr("/", kScene))
    throw InputError(f.path() + ": filtered file lacks the root attribute 'scene' (the first run's scene text)");
  s.scene_toml = f.attr_string("/", kScene);
  s.system = read_physical_system(f, names::kMicroLawAttribute, "filtered file");
  if (!(s.system.l_char_m > 0))
    throw InputError(f.path() + ": attribute 'l_char_m' of '/' is " + number(s.system.l_char_m) + ", expected > 0");
  s.parcel_size = optional_finite(f, "/", kParcelSize);
  if (f.has_attr("/", kCellSize)) s.cell_size_m = finite_attrs(f, "/", kCellSize, 3);
  if (f.has_attr("/", kPressureTerms)) s.pressure_terms = f.attr_int("/", kPressureTerms) != 0;
  if (f.has_attr("/", kBootstrapReplicates)) s.bootstrap_replicates = f.attr_int("/", kBootstrapReplicates);
  if (f.has_attr("/", kBootstrapSeed)) s.bootstrap_seed = f.attr_int("/", kBootstrapSeed);
  s.confidence = optional_finite(f, "/", kConfidence);
  if (f.has_attr("/", kBootstrap)) s.bootstrap = f.attr_string("/", kBootstrap);
}

void read_runs_and_snapshots(const h5::File& f, Filtered& s) {
  const std::string& path = f.path();
  s.phi_edges = read_doubles(f, kPhiEdges, {kAnyExtent}, Finite::Everywhere);
  if (s.phi_edges.size() < 2 ||
      std::adjacent_find(s.phi_edges.begin(), s.phi_edges.end(), std::greater_equal<>()) != s.phi_edges.end())
    throw InputError(path + ": dataset '/bins/phi_edges' holds " + std::to_string(s.phi_edges.size()) +
                     " edges, expected at least two, strictly increasing");
  if (f.exists(kSlipEdges)) {  // the drift sums' slip bins (absent in files written before them)
    s.slip_edges = read_doubles(f, kSlipEdges, {kAnyExtent}, Finite::Everywhere);
    if (s.slip_edges.size() < 2 ||
        std::adjacent_find(s.slip_edges.begin(), s.slip_edges.end(), std::greater_equal<>()) != s.slip_edges.end())
      throw InputError(path + ": dataset '/bins/slip_edges' holds " + std::to_string(s.slip_edges.size()) +
                       " edges, expected at least two, strictly increasing");
  }
  s.run_mean_solids_fraction = read_doubles(f, "/runs/mean_solids_fraction", {kAnyExtent}, Finite::Everywhere);
  const std::uint64_t nr = s.run_mean_solids_fraction.size();
  s.run_paths = f.has_attr(kRuns, "paths") ? f.attr_strings(kRuns, "paths") : std::vector<std::string>{};
  if (s.run_paths.size() != nr) s.run_paths.resize(nr, path);
  const std::string per_run = "one row per run, the length of /runs/mean_solids_fraction";
  s.run_snapshot_count = read_ints(f, "/runs/snapshot_count", {nr}, per_run);
  s.run_block_length = optional_ints(f, "/runs/block_length", {nr}, per_run);
  s.run_tau_int = optional_doubles(f, "/runs/tau_int", {nr}, Finite::Not, per_run);
  s.run_n_eff = optional_doubles(f, "/runs/n_eff", {nr}, Finite::Not, per_run);

  s.snapshot_run_index = read_ints(f, "/snapshots/run_index", {kAnyExtent});
  const std::uint64_t ns = s.snapshot_run_index.size();
  const std::string per_snapshot = "one row per snapshot, the length of /snapshots/run_index";
  s.snapshot_block = read_ints(f, "/snapshots/block", {ns}, per_snapshot);
  s.snapshot_step = optional_ints(f, "/snapshots/step", {ns}, per_snapshot);
  s.snapshot_time_s = optional_doubles(f, "/snapshots/time_s", {ns}, Finite::Everywhere, per_snapshot);
  if (f.has_attr(kSnapshots, "files")) s.snapshot_files = f.attr_strings(kSnapshots, "files");
  if (f.has_attr(kSnapshots, "checksums")) s.snapshot_checksums = f.attr_strings(kSnapshots, "checksums");
  std::int64_t listed = 0;
  for (std::int64_t c : s.run_snapshot_count) listed += c;
  if (listed != static_cast<std::int64_t>(ns))
    throw InputError(path + ": dataset '/runs/snapshot_count' sums to " + std::to_string(listed) +
                     " snapshots, expected " + std::to_string(ns) + " (the rows of /snapshots/run_index)");
  for (std::int64_t r : s.snapshot_run_index)
    if (r < 0 || static_cast<std::uint64_t>(r) >= nr)
      throw InputError(path + ": dataset '/snapshots/run_index' holds " + std::to_string(r) + ", expected [0, " +
                       std::to_string(nr) + ")");
}

Grid read_grid_attributes(const h5::File& f, const std::string& g, std::int64_t version) {
  Grid c;
  for (const char* key : {"cells_across", "cell_size_over_dp"})
    if (!f.has_attr(g, key)) throw InputError(f.path() + ": grid group '" + g + "' lacks the attribute '" + key + "'");
  c.cells_across = f.attr_int(g, "cells_across");
  c.cell_size_over_dp = finite_attr(f, g, "cell_size_over_dp");
  if (!(c.cell_size_over_dp > 0))
    throw InputError(f.path() + ": attribute 'cell_size_over_dp' of '" + g + "' is " + number(c.cell_size_over_dp) +
                     ", expected > 0");
  if (f.has_attr(g, "cells")) c.cells = f.attr_ints(g, "cells");
  if (f.has_attr(g, "cell_spacing_m")) c.cell_spacing_m = finite_attrs(f, g, "cell_spacing_m", 3);
  for (const auto& n : kGridNumbers) c.*n.member = optional_finite(f, g, n.name);
  for (const auto& n : kEquivalentNumbers)
    if (f.has_attr(g, n.name)) c.*n.member = f.attr_double(g, n.name);
  if (f.has_attr(g, "equivalent_width_rms")) c.equivalent_width_rms = f.attr_double(g, "equivalent_width_rms");
  if (f.has_attr(g, "equivalent_width_bins")) c.equivalent_width_bins = f.attr_int(g, "equivalent_width_bins");
  if (f.has_attr(g, "equivalent_width_at_bound"))
    c.equivalent_width_at_bound = f.attr_int(g, "equivalent_width_at_bound") != 0;
  if (f.has_attr(g, "equivalent_width_method")) c.equivalent_width_method = f.attr_string(g, "equivalent_width_method");
  require_grid_operator(f, g, version);
  return c;
}

/// `drift/` of a grid group: the totals of shape (n_bins, n_slip), count int64 >= 0, the sums finite; per_snapshot/
/// (where present) of shape (n_snapshots, n_bins, n_slip), its count summing to the totals'.
Drift read_drift(const h5::File& f, const std::string& g, std::uint64_t ns, std::uint64_t nb, std::uint64_t n_slip) {
  const std::string& path = f.path();
  const std::string dg = g + "/drift";
  if (n_slip == 0)
    throw InputError(path + ": group '" + dg + "' is present but '/bins/slip_edges' is not (the slip bins of its sums)");
  Drift d;
  if (f.has_attr(dg, "out_of_range")) d.out_of_range = f.attr_int(dg, "out_of_range");
  const std::string shape = "(n_bins, n_slip) = (" + std::to_string(nb) + ", " + std::to_string(n_slip) + ")";
  d.count = read_ints(f, dg + "/count", {nb, n_slip}, shape);
  for (std::size_t k = 0; k < d.count.size(); ++k)
    if (d.count[k] < 0)
      throw InputError(path + ": dataset '" + dg + "/count' holds " + std::to_string(d.count[k]) + ", expected counts >= 0");
  for (const DriftNumber& n : kDriftNumbers)
    if (n.finite == Finite::Everywhere || f.exists(dg + "/" + n.name))
      d.*n.member = read_doubles(f, dg + "/" + n.name, {nb, n_slip}, n.finite, shape);
  const std::string ps = dg + "/per_snapshot";
  if (f.exists(ps + "/count")) {
    Drift::PerSnapshot p;
    const std::string pshape = "(n_snapshots, n_bins, n_slip) = (" + std::to_string(ns) + ", " + std::to_string(nb) +
                               ", " + std::to_string(n_slip) + ")";
    p.count = read_ints(f, ps + "/count", {ns, nb, n_slip}, pshape);
    p.numerator = read_doubles(f, ps + "/numerator", {ns, nb, n_slip}, Finite::Everywhere, pshape);
    p.denominator = read_doubles(f, ps + "/denominator", {ns, nb, n_slip}, Finite::Everywhere, pshape);
    const std::size_t cells = static_cast<std::size_t>(nb * n_slip);
    for (std::size_t c = 0; c < cells; ++c) {
      std::int64_t sum = 0;
      for (std::size_t k = 0; k < ns; ++k) sum += p.count[k * cells + c];
      if (sum != d.count[c])
        throw InputError(path + ": dataset '" + ps + "/count' sums to " + std::to_string(sum) + " samples in (phi bin " +
                         std::to_string(c / n_slip) + ", slip bin " + std::to_string(c % n_slip) + "), expected " +
                         std::to_string(d.count[c]) + " (" + dg + "/count)");
    }
    d.per_snapshot = std::move(p);
  }
  return d;
}

Group read_group(const h5::File& f, const std::string& g, FilterKind kind, std::int64_t version, bool per_snapshot, std::uint64_t ns,
                 std::uint64_t nb, std::uint64_t n_slip) {
  const std::string& path = f.path();
  Group w;
  w.kind = kind;
  require_kind(f, g, kind);
  if (!f.has_attr(g, "F")) throw InputError(path + ": group '" + g + "' lacks the attribute 'F' (L_char / width)");
  w.F = finite_attr(f, g, "F");
  if (!(w.F > 0)) throw InputError(path + ": attribute 'F' of '" + g + "' is " + number(w.F) + ", expected > 0");
  for (const auto& n : kGroupNumbers) w.*n.member = optional_finite(f, g, n.name);
  if (f.has_attr(g, "out_of_range")) w.out_of_range = f.attr_int(g, "out_of_range");
  if (kind == FilterKind::Grid) w.grid = read_grid_attributes(f, g, version);

  const std::string per_bin = "n_bins = len(/bins/phi_edges) - 1 = " + std::to_string(nb);
  w.count = read_ints(f, g + "/count", {nb}, per_bin);
  for (std::size_t b = 0; b < nb; ++b)
    if (w.count[b] < 0)
      throw InputError(path + ": dataset '" + g + "/count' holds " + std::to_string(w.count[b]) + " in bin " +
                       std::to_string(b) + ", expected counts >= 0");
  for (const PerBin& b : kPerBin) {
    const std::string name = g + "/" + b.name;
    if (!b.required && !f.exists(name)) continue;
    w.*b.member = read_doubles(f, name, {nb}, Finite::Not, per_bin);
    if (b.finite_where_counted) require_finite_where_counted(path, name, w.*b.member, w.count);
  }
  if (per_snapshot) {
    PerSnapshot p;
    const std::string ps = g + "/per_snapshot";
    const std::string shape = "(n_snapshots, n_bins) = (" + std::to_string(ns) + ", " + std::to_string(nb) + ")";
    for (const SnapshotSums& s : kSnapshotSums)
      if (s.required || f.exists(ps + "/" + s.name))
        p.*s.member = read_doubles(f, ps + "/" + s.name, {ns, nb}, s.required ? Finite::Everywhere : Finite::Not, shape);
    p.count = read_ints(f, ps + "/count", {ns, nb}, shape);
    for (std::size_t b = 0; b < nb; ++b) {
      std::int64_t sum = 0;
      for (std::size_t k = 0; k < ns; ++k) sum += p.count[k * nb + b];
      if (sum != w.count[b])
        throw InputError(path + ": dataset '" + ps + "/count' sums to " + std::to_string(sum) + " samples in bin " +
                         std::to_string(b) + ", expected " + std::to_string(w.count[b]) + " (" + g + "/count)");
    }
    w.per_snapshot = std::move(p);
  }
  if (kind == FilterKind::Grid && f.exists(g + "/drift")) w.drift = read_drift(f, g, ns, nb, n_slip);
  if (f.exists(g + "/samples")) {
    Samples s;
    const std::string sg = g + "/samples";
    s.phi = read_doubles(f, sg + "/phi", {kAnyExtent}, Finite::Not);
    const std::uint64_t n = s.phi.size();
    const std::string rows = "one row per sample, the length of " + sg + "/phi";
    for (const SampleColumn& c : kSampleColumns)
      if (c.member != &Samples::phi)
        s.*c.member = read_doubles(f, sg + "/" + c.name,
                                   c.width == 1 ? std::vector<std::uint64_t>{n} : std::vector<std::uint64_t>{n, c.width},
                                   Finite::Not, rows);
    s.snapshot = read_ints(f, sg + "/snapshot", {n}, rows);
    s.id = read_ints(f, sg + "/id", {n}, rows);
    w.samples = std::move(s);
  }
  return w;
}

}  // namespace

const char* to_string(FilterKind kind) {
  switch (kind) {
    case FilterKind::Box: return "box";
    case FilterKind::WholeBox: return "whole_box";
    case FilterKind::Grid: return "grid";
  }
  return "box";
}

std::string group_path(const FilteredGroup& group, std::size_t box_index) {
  switch (group.kind) {
    case FilterKind::WholeBox: return kWholeBox;
    case FilterKind::Grid: return std::string(kGrids) + "/" + std::to_string(group.grid ? group.grid->cells_across : 0);
    case FilterKind::Box: break;
  }
  return kWidthPrefix + std::to_string(box_index);
}

std::vector<std::string> group_paths(const Filtered& file) {
  std::vector<std::string> out;
  std::size_t boxes = 0;
  for (const FilteredGroup& g : file.groups) {
    out.push_back(group_path(g, boxes));
    if (g.kind == FilterKind::Box) ++boxes;
  }
  return out;
}

void write_filtered(const std::string& path, const Scene* scene, const Filtered& s) {
  const std::vector<std::string> paths = group_paths(s);
  std::vector<std::int64_t> across;
  for (const FilteredGroup& g : s.groups)
    if (g.kind == FilterKind::Grid && g.grid) across.push_back(g.grid->cells_across);
  h5::write_atomically(path, MPI_COMM_SELF, [&](h5::File& f) {
    write_root(f, scene, s);
    write_runs_and_snapshots(f, s);
    if (!across.empty()) {
      f.create_group(kGrids);
      f.set_attr(kGrids, "cells_across", across);
      f.set_attr(kGrids, "operator", std::string(to_string(CalibrationOperator::Grid)));
      f.set_attr(kGrids, "definition", std::string(kGridsDefinition));
    }
    for (std::size_t i = 0; i < s.groups.size(); ++i)
      write_group(f, paths[i], s.groups[i], s.snapshot_run_index.size(), s.bins(), s.slip_bins());
  });
}

Filtered read_filtered(const std::string& path) {
  h5::File f = h5::File::open_read(path, MPI_COMM_SELF);
  Filtered s;
  s.version = check_format(f, kFiltered);
  read_root(f, s);
  read_runs_and_snapshots(f, s);
  const std::uint64_t ns = s.snapshot_run_index.size(), nb = s.bins();
  // the groups: /width_0, /width_1, ... then /whole_box, then /grids/<N> in the order /grids lists them
  std::vector<std::pair<std::string, FilterKind>> groups;
  for (int k = 0; f.exists(kWidthPrefix + std::to_string(k)); ++k)
    groups.emplace_back(kWidthPrefix + std::to_string(k), FilterKind::Box);
  if (f.exists(kWholeBox)) groups.emplace_back(kWholeBox, FilterKind::WholeBox);
  if (f.exists(kGrids) && f.has_attr(kGrids, "cells_across")) {
    require_grid_operator(f, kGrids, s.version);
    for (std::int64_t n : f.attr_ints(kGrids, "cells_across")) {
      const std::string g = std::string(kGrids) + "/" + std::to_string(n);
      if (!f.exists(g))
        throw InputError(path + ": attribute 'cells_across' of '/grids' lists " + std::to_string(n) +
                         ", expected its group " + g + ", which is absent");
      groups.emplace_back(g, FilterKind::Grid);
    }
  }
  // the per-snapshot sums are in every group or in none (the first decides)
  const bool per_snapshot = !groups.empty() && f.exists(groups.front().first + "/per_snapshot/numerator");
  for (const auto& [g, kind] : groups)
    s.groups.push_back(read_group(f, g, kind, s.version, per_snapshot, ns, nb, s.slip_bins()));
  for (const FilteredGroup& g : s.groups)
    if (g.kind == FilterKind::Grid && g.grid && g.grid->cells_across <= 0)
      throw InputError(path + ": attribute 'cells_across' of a grid group is " + std::to_string(g.grid->cells_across) +
                       ", expected > 0");
  return s;
}

}  // namespace cgd::schema
