// The drag model file's write and validating read (core/schema/drag_model.hpp, docs/schema-drag-model.md).
#include "core/schema/drag_model.hpp"

#include <algorithm>
#include <cstdio>
#include <functional>

#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/schema/common.hpp"
#include "core/schema/check.hpp"

namespace cgd::schema {

namespace {

using M = DragModelFile;

// root
constexpr const char* kModelForm = "model_form";
constexpr const char* kWidthExponent = "width_exponent";
constexpr const char* kWidthExponentFitted = "width_exponent_fitted";
constexpr const char* kWidthExponentLow = "width_exponent_low";
constexpr const char* kWidthExponentHigh = "width_exponent_high";
constexpr const char* kOperator = "operator";
constexpr const char* kKernel = "kernel";
constexpr const char* kCurves = "curves";
constexpr const char* kTableCellsAcross = "table_cells_across";
constexpr const char* kCalibratedDelta = "calibrated_delta_m";
constexpr const char* kCalibratedDeltaOverDp = "calibrated_delta_over_dp";
constexpr const char* kCalibratedCellsAcross = "calibrated_cells_across";
constexpr const char* kUtConventionAttribute = "u_t_convention";
constexpr const char* kPhiCrit = "phi_crit";
constexpr const char* kPhiMax = "phi_max";
constexpr const char* kHMax = "h_max";
constexpr const char* kLogAMin = "log_a_min";
constexpr const char* kLogAMax = "log_a_max";
// groups
constexpr const char* kH = "/h";
constexpr const char* kLogA = "/log_a";
constexpr const char* kCCorr = "/c_corr";
constexpr const char* kBands = "/bands";
constexpr const char* kBins = "/bins";
constexpr const char* kData = "/data";
constexpr const char* kDiagnostics = "/diagnostics";
constexpr const char* kTable = "/table";
constexpr const char* kDriftTable = "/drift_table";
constexpr const char* kSources = "/sources";
constexpr const char* kProvenance = "/provenance";
constexpr const char* kProvenanceKeys[] = {"made_by", "resolved_runs", "valid_for", "validation"};
constexpr const char* kCCorrFormula = "c_corr = a + (1 - a) exp(-k (alpha - 1))";
constexpr const char* kChecksumKind = "FNV-1a 64-bit of the file's bytes, hex";

/// The spellings that changed with version 2 (docs/schema-drag-model.md "Versions"): version 2 stores the
/// micro law under `micro_drag` and the grid operator as "grid", the spellings of the filtered file and of
/// cgd-fit --operator; version 1 (the files written before, among them data/models/half_box.h5, whose
/// checksum runs and exports record) stored `base_drag` and "tsc-grid". The one upgrade path: upgrade_version1
/// maps these two spellings of a version-1 file and nothing else; a version-2 file must use the new ones.
constexpr const char* kVersion1MicroLawAttribute = "base_drag";
constexpr const char* kVersion1GridOperator = "tsc-grid";
struct Spelling {
  const char* law_attribute;
  const char* grid_operator;
};
Spelling upgrade_version1(std::int64_t version) {
  if (version == 1) return {kVersion1MicroLawAttribute, kVersion1GridOperator};
  return {names::kMicroLawAttribute, to_string(CalibrationOperator::Grid)};
}

/// Named members of a group's struct, for writing and reading them alike.
template <class S>
struct Vec {
  const char* name;
  std::vector<double> S::*member;
};
template <class S>
struct Ints {
  const char* name;
  std::vector<std::int64_t> S::*member;
};
template <class S>
struct Num {
  const char* name;
  double S::*member;
};
template <class S>
struct Int {
  const char* name;
  std::int64_t S::*member;
};

using Bands = M::Bands;
constexpr Vec<Bands> kBandCurves[] = {{"phi", &Bands::phi}, {"h", &Bands::h},         {"h_low", &Bands::h_low},
                                      {"h_high", &Bands::h_high}, {"a", &Bands::a},   {"a_low", &Bands::a_low},
                                      {"a_high", &Bands::a_high}, {"F", &Bands::F}};
constexpr Vec<Bands> kBandSurfaces[] = {{"H", &Bands::H}, {"H_low", &Bands::H_low}, {"H_high", &Bands::H_high}};

using Bins = M::Bins;
constexpr Vec<Bins> kBinNumbers[] = {{"phi", &Bins::phi},
                                     {"phi_center", &Bins::phi_center},
                                     {"h", &Bins::h},
                                     {"h_stderr", &Bins::h_stderr},
                                     {"a", &Bins::a},
                                     {"log_a_stderr", &Bins::log_a_stderr},
                                     {"chi2", &Bins::chi2},
                                     {"h_stderr_bootstrap", &Bins::h_stderr_bootstrap},
                                     {"log_a_stderr_bootstrap", &Bins::log_a_stderr_bootstrap}};
constexpr Ints<Bins> kBinFlags[] = {
    {"used", &Bins::used}, {"widths", &Bins::widths}, {"at_bound", &Bins::at_bound}, {"a_at_cap", &Bins::a_at_cap}};

using Diagnostics = M::Diagnostics;
constexpr Int<Diagnostics> kDiagnosticInts[] = {{"min_count", &Diagnostics::min_count},
                                                {"min_widths", &Diagnostics::min_widths},
                                                {"breakpoints", &Diagnostics::breakpoints},
                                                {"h_clamped_grid_points", &Diagnostics::h_clamped_grid_points}};
constexpr Num<Diagnostics> kDiagnosticNumbers[] = {{"min_width_over_cell", &Diagnostics::min_width_over_cell},
                                                   {"lambda_h", &Diagnostics::lambda_h},
                                                   {"lambda_log_a", &Diagnostics::lambda_log_a},
                                                   {"edf_h", &Diagnostics::edf_h},
                                                   {"edf_log_a", &Diagnostics::edf_log_a},
                                                   {"chi2_per_dof", &Diagnostics::chi2_per_dof},
                                                   {"cv_rms_H", &Diagnostics::cv_rms_H},
                                                   {"cv_in_sample_rms_H", &Diagnostics::cv_in_sample_rms_H},
                                                   {"wall_seconds", &Diagnostics::wall_seconds}};
constexpr Vec<Diagnostics> kResidualNumbers[] = {{"residual_F", &Diagnostics::residual_F},
                                                 {"residual_mean", &Diagnostics::residual_mean},
                                                 {"residual_mean_z", &Diagnostics::residual_mean_z},
                                                 {"residual_rms_z", &Diagnostics::residual_rms_z},
                                                 {"residual_mean_smoothed", &Diagnostics::residual_mean_smoothed}};
constexpr Vec<Diagnostics> kCrossValidationNumbers[] = {{"cv_rms", &Diagnostics::cv_rms},
                                                        {"cv_mean", &Diagnostics::cv_mean}};
constexpr Ints<Diagnostics> kCrossValidationInts[] = {{"cv_run", &Diagnostics::cv_run},
                                                      {"cv_points", &Diagnostics::cv_points}};

using Table = M::Table;
constexpr Vec<Table> kTableColumns[] = {{"phi", &Table::phi}, {"H", &Table::H}, {"count", &Table::count}};

using Drift = M::DriftTable;
// (n_phi, n_slip) float datasets of /drift_table: H finite everywhere (the law reads it), the pooled sums not
constexpr Vec<Drift> kDriftSums[] = {
    {"numerator", &Drift::numerator}, {"denominator", &Drift::denominator}, {"magnitude", &Drift::magnitude}};
constexpr Ints<Drift> kDriftInts[] = {{"count", &Drift::count}, {"filled", &Drift::filled}};

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

std::string child(const char* group, const char* name) { return std::string(group) + "/" + name; }

// ---- write --------------------------------------------------------------------------------------

void write_vector(h5::File& f, const std::string& name, const std::vector<double>& v) {
  f.write_replicated(name, v, {v.size()});
}
void write_vector(h5::File& f, const std::string& name, const std::vector<std::int64_t>& v) {
  f.write_replicated(name, v, {v.size()});
}

void write_root(h5::File& f, const M& m) {
  f.set_attr("/", kModelForm, m.model_form);
  f.set_attr("/", kWidthExponent, m.width_exponent);
  f.set_attr("/", kWidthExponentFitted, std::int64_t{m.width_exponent_fitted ? 1 : 0});
  if (m.width_exponent_fitted) {
    f.set_attr("/", kWidthExponentLow, m.width_exponent_low);
    f.set_attr("/", kWidthExponentHigh, m.width_exponent_high);
  }
  const bool grid = m.calibration_operator == CalibrationOperator::Grid;
  f.set_attr("/", kOperator, std::string(to_string(m.calibration_operator)));
  if (grid) f.set_attr("/", kKernel, std::string("tsc"));
  f.set_attr("/", kCurves, std::string(to_string(m.curves)));
  if (m.curves != ModelCurves::Splines) f.set_attr("/", kTableCellsAcross, m.table_cells_across);
  if (!m.calibrated_delta_m.empty()) {
    f.set_attr("/", kCalibratedDelta, m.calibrated_delta_m);
    f.set_attr("/", kCalibratedDeltaOverDp, m.calibrated_delta_over_dp);
  }
  if (grid && !m.calibrated_cells_across.empty()) f.set_attr("/", kCalibratedCellsAcross, m.calibrated_cells_across);
  write_physical_system(f, m.system, names::kMicroLawAttribute);
  f.set_attr("/", kUtConventionAttribute, m.u_t_convention);
  f.set_attr("/", kPhiCrit, m.phi_crit);
  f.set_attr("/", kPhiMax, m.phi_max);
  f.set_attr("/", kHMax, m.h_max);
  if (m.curves == ModelCurves::Splines) {
    f.set_attr("/", kLogAMin, m.log_a_min);
    f.set_attr("/", kLogAMax, m.log_a_max);
  }
}

void write_spline(h5::File& f, const char* group, const SplineRecord& s) {
  f.create_group(group);
  f.set_attr(group, "order", static_cast<std::int64_t>(s.order));
  f.set_attr(group, "meaning", s.meaning);
  write_vector(f, child(group, "knots"), s.knots);
  write_vector(f, child(group, "coefficients"), s.coefficients);
}

using ParcelFit = M::CCorr::ParcelFit;
constexpr Num<ParcelFit> kParcelFitNumbers[] = {{"a_fit", &ParcelFit::a_fit},
                                                {"k_fit", &ParcelFit::k_fit},
                                                {"p_value", &ParcelFit::p_value},
                                                {"k_lower_bound", &ParcelFit::k_lower_bound},
                                                {"chi2_per_dof", &ParcelFit::chi2_per_dof}};
constexpr Vec<ParcelFit> kParcelFitRuns[] = {{"runs_alpha", &ParcelFit::runs_alpha},
                                             {"runs_phi", &ParcelFit::runs_phi},
                                             {"runs_factor", &ParcelFit::runs_factor},
                                             {"runs_factor_stderr", &ParcelFit::runs_factor_stderr},
                                             {"runs_seed", &ParcelFit::runs_seed}};

void write_parcel_fit(h5::File& f, const ParcelFit& p) {
  for (const auto& n : kParcelFitNumbers) f.set_attr(kCCorr, n.name, p.*n.member);
  f.set_attr(kCCorr, "dof", p.dof);
  f.set_attr(kCCorr, "applied", std::int64_t{p.applied ? 1 : 0});
  f.set_attr(kCCorr, "rejected", std::int64_t{p.rejected ? 1 : 0});
  f.set_attr(kCCorr, "a_fitted", std::int64_t{p.a_fitted ? 1 : 0});
  f.set_attr(kCCorr, "decision", p.decision);
  f.set_attr(kCCorr, "method", p.method);
  f.set_attr(kCCorr, "k_interval", p.k_interval);
  f.set_attr(kCCorr, "a_interval", p.a_interval);
  f.set_attr(kCCorr, "runs", p.runs);
  for (const auto& v : kParcelFitRuns) f.set_attr(kCCorr, v.name, p.*v.member);
}

/// The attributes of an existing /c_corr.
void write_c_corr_attributes(h5::File& f, const M::CCorr& c) {
  f.set_attr(kCCorr, "a", c.a);
  f.set_attr(kCCorr, "k", c.k);
  f.set_attr(kCCorr, "source", c.source);
  f.set_attr(kCCorr, "fitted", std::int64_t{c.fitted ? 1 : 0});
  f.set_attr(kCCorr, "formula", std::string(kCCorrFormula));
  if (c.parcel_fit) write_parcel_fit(f, *c.parcel_fit);
}

void write_c_corr(h5::File& f, const M::CCorr& c) {
  f.create_group(kCCorr);
  write_c_corr_attributes(f, c);
}

void write_bands(h5::File& f, const Bands& b) {
  f.create_group(kBands);
  f.set_attr(kBands, "replicates", b.replicates);
  f.set_attr(kBands, "seed", b.seed);
  f.set_attr(kBands, "confidence", b.confidence);
  f.set_attr(kBands, "resampling", b.resampling);
  for (const auto& v : kBandCurves) write_vector(f, child(kBands, v.name), b.*v.member);
  for (const auto& v : kBandSurfaces) f.write_replicated(child(kBands, v.name), b.*v.member, {b.F.size(), b.phi.size()});
}

void write_bins(h5::File& f, const Bins& b) {
  f.create_group(kBins);
  for (const auto& v : kBinNumbers) write_vector(f, child(kBins, v.name), b.*v.member);
  for (const auto& v : kBinFlags) write_vector(f, child(kBins, v.name), b.*v.member);
}

void write_data(h5::File& f, const M::Data& d) {
  f.create_group(kData);
  f.set_attr(kData, "series", d.series);
  write_vector(f, child(kData, "F"), d.F);
  write_vector(f, child(kData, "phi"), d.phi);
  f.write_replicated(child(kData, "H"), d.H, {d.F.size(), d.phi.size()});
  f.write_replicated(child(kData, "H_sigma"), d.H_sigma, {d.F.size(), d.phi.size()});
  write_vector(f, child(kData, "fitted"), d.fitted);
}

void write_diagnostics(h5::File& f, const Diagnostics& d) {
  f.create_group(kDiagnostics);
  for (const auto& n : kDiagnosticInts) f.set_attr(kDiagnostics, n.name, d.*n.member);
  for (const auto& n : kDiagnosticNumbers) f.set_attr(kDiagnostics, n.name, d.*n.member);
  if (!d.width_exponent_grid.empty()) {
    write_vector(f, child(kDiagnostics, "width_exponent_grid"), d.width_exponent_grid);
    write_vector(f, child(kDiagnostics, "width_exponent_chi2"), d.width_exponent_chi2);
    f.set_attr(kDiagnostics, "width_exponent_chi2_per_dof", d.width_exponent_chi2_per_dof);
  }
  f.set_attr(kDiagnostics, "residual_files", d.residual_files);
  f.set_attr(kDiagnostics, "residual_groups", d.residual_groups);
  for (const auto& v : kResidualNumbers) write_vector(f, child(kDiagnostics, v.name), d.*v.member);
  write_vector(f, child(kDiagnostics, "residual_points"), d.residual_points);
  if (!d.cv_run.empty()) {
    f.set_attr(kDiagnostics, "cv_files", d.cv_files);
    for (const auto& v : kCrossValidationInts) write_vector(f, child(kDiagnostics, v.name), d.*v.member);
    for (const auto& v : kCrossValidationNumbers) write_vector(f, child(kDiagnostics, v.name), d.*v.member);
  }
}

void write_table(h5::File& f, const Table& t) {
  f.create_group(kTable);
  for (const auto& v : kTableColumns) write_vector(f, child(kTable, v.name), t.*v.member);
  f.set_attr(kTable, "source_group", t.source_group);
  f.set_attr(kTable, "min_count", t.min_count);
}

void write_drift_table(h5::File& f, const Drift& t) {
  f.create_group(kDriftTable);
  const std::vector<std::uint64_t> shape{t.phi.size(), t.slip.size()};
  write_vector(f, child(kDriftTable, "phi"), t.phi);
  write_vector(f, child(kDriftTable, "slip"), t.slip);
  f.write_replicated(child(kDriftTable, "H"), t.H, shape);
  for (const auto& v : kDriftSums) f.write_replicated(child(kDriftTable, v.name), t.*v.member, shape);
  for (const auto& v : kDriftInts) f.write_replicated(child(kDriftTable, v.name), t.*v.member, shape);
  write_vector(f, child(kDriftTable, "phi_only_H"), t.phi_only_H);
  f.set_attr(kDriftTable, "source_group", t.source_group);
  f.set_attr(kDriftTable, "fill_rule", t.fill_rule);
  f.set_attr(kDriftTable, "min_count", t.min_count);
  f.set_attr(kDriftTable, "min_alignment", t.min_alignment);
  f.set_attr(kDriftTable, "phi_bin_width", t.phi_bin_width);
  f.set_attr(kDriftTable, "slip_bin_width", t.slip_bin_width);
  f.set_attr(kDriftTable, "slip_unit", std::string("u_t"));
}

void write_sources(h5::File& f, const M& m) {
  f.create_group(kSources);
  f.set_attr(kSources, "files", m.source_files);
  f.set_attr(kSources, "checksums", m.source_checksums);
  f.set_attr(kSources, "checksum_kind", std::string(kChecksumKind));
  f.set_attr(kSources, "pooled_runs", static_cast<std::int64_t>(m.sources_pooled ? 1 : 0));
}

// ---- read ---------------------------------------------------------------------------------------

void refuse(const h5::File& f, const std::string& what) { throw InputError(f.path() + ": " + what); }

void require_attr(const h5::File& f, const char* object, const char* name) {
  if (!f.has_attr(object, name))
    refuse(f, std::string("drag model file lacks the attribute '") + name + "' of '" + object + "'");
}

void require_group(const h5::File& f, const char* group) {
  if (!f.exists(group)) refuse(f, std::string("drag model file lacks the group '") + group + "'");
}

/// A float attribute that must be finite and inside (low, high) (high inclusive when `high_inclusive`).
double bounded(const h5::File& f, const char* name, double low, double high, bool high_inclusive) {
  const double v = finite_attr(f, "/", name);
  if (!(v > low && (high_inclusive ? v <= high : v < high)))
    refuse(f, std::string("attribute '") + name + "' of '/' is " + number(v) + ", expected a number in (" +
                  number(low) + ", " + number(high) + (high_inclusive ? "]" : ")"));
  return v;
}

SplineRecord read_spline(const h5::File& f, const char* group) {
  require_group(f, group);
  require_attr(f, group, "order");
  SplineRecord s;
  const std::int64_t order = f.attr_int(group, "order");
  if (order < 1 || order > 15)
    refuse(f, std::string("attribute 'order' of '") + group + "' is " + std::to_string(order) +
                  ", expected an integer in [1, 15]");
  s.order = static_cast<int>(order);
  if (f.has_attr(group, "meaning")) s.meaning = f.attr_string(group, "meaning");
  s.coefficients = read_doubles(f, child(group, "coefficients"), {kAnyExtent}, Finite::Everywhere);
  const std::uint64_t n = s.coefficients.size();
  if (n < static_cast<std::uint64_t>(s.order))
    refuse(f, std::string("dataset '") + group + "/coefficients' holds " + std::to_string(n) +
                  " values, expected at least order = " + std::to_string(s.order));
  s.knots = read_doubles(f, child(group, "knots"), {n + static_cast<std::uint64_t>(s.order)}, Finite::Everywhere,
                         "len(coefficients) + order");
  if (!std::is_sorted(s.knots.begin(), s.knots.end()) ||
      !(s.knots[n] > s.knots[static_cast<std::size_t>(s.order - 1)]))
    refuse(f, std::string("dataset '") + group + "/knots' is not a knot vector: expected non-decreasing knots "
                  "spanning an interval");
  return s;
}

void read_calibration(const h5::File& f, M& m, const Spelling& spelling) {
  if (f.has_attr("/", kOperator)) {
    const std::string text = f.attr_string("/", kOperator);
    const char* box = to_string(CalibrationOperator::Box);
    if (text != box && text != spelling.grid_operator)
      refuse(f, "attribute 'operator' of '/' is \"" + text + "\", expected \"" + box + "\" or \"" +
                    spelling.grid_operator + "\" (cgd_format_version " + std::to_string(m.version) + ")");
    m.calibration_operator = text == box ? CalibrationOperator::Box : CalibrationOperator::Grid;
  }
  if (f.has_attr("/", kCurves)) {
    const std::string text = f.attr_string("/", kCurves);
    if (text == to_string(ModelCurves::Splines)) m.curves = ModelCurves::Splines;
    else if (text == to_string(ModelCurves::Table)) m.curves = ModelCurves::Table;
    else if (text == to_string(ModelCurves::DriftTable)) m.curves = ModelCurves::DriftTable;
    else refuse(f, "attribute 'curves' of '/' is \"" + text + "\", expected \"splines\", \"table\" or \"drift_table\"");
  }
  if (f.has_attr("/", kCalibratedDelta)) m.calibrated_delta_m = finite_attrs(f, "/", kCalibratedDelta);
  if (f.has_attr("/", kCalibratedDeltaOverDp)) m.calibrated_delta_over_dp = finite_attrs(f, "/", kCalibratedDeltaOverDp);
  if (f.has_attr("/", kCalibratedCellsAcross)) m.calibrated_cells_across = f.attr_ints("/", kCalibratedCellsAcross);
  if (f.has_attr("/", kTableCellsAcross)) m.table_cells_across = f.attr_int("/", kTableCellsAcross);
}

void read_root(const h5::File& f, M& m) {
  for (const char* key : {kUtConventionAttribute, kPhiCrit, kHMax}) require_attr(f, "/", key);
  const Spelling spelling = upgrade_version1(m.version);
  m.system = read_physical_system(f, spelling.law_attribute, "drag model file");
  if (!(m.system.l_char_m > 0))
    refuse(f, "attribute 'l_char_m' of '/' is " + number(m.system.l_char_m) + ", expected > 0");
  m.u_t_convention = f.attr_string("/", kUtConventionAttribute);
  if (m.u_t_convention != kUtConvention)
    refuse(f, "attribute 'u_t_convention' of '/' is \"" + m.u_t_convention + "\", expected \"" + kUtConvention +
                  "\" (docs/models.md)");
  m.phi_crit = bounded(f, kPhiCrit, 0, 1, false);
  m.h_max = bounded(f, kHMax, 0, 1, false);
  // width_exponent arrived after version 1's first files: absent means the paper's form (n = 1)
  m.width_exponent = f.has_attr("/", kWidthExponent) ? bounded(f, kWidthExponent, 0, 10, true) : 1.0;
  if (f.has_attr("/", kWidthExponentFitted)) m.width_exponent_fitted = f.attr_int("/", kWidthExponentFitted) != 0;
  if (f.has_attr("/", kWidthExponentLow)) m.width_exponent_low = f.attr_double("/", kWidthExponentLow);
  if (f.has_attr("/", kWidthExponentHigh)) m.width_exponent_high = f.attr_double("/", kWidthExponentHigh);
  if (f.has_attr("/", kPhiMax)) m.phi_max = finite_attr(f, "/", kPhiMax);
  if (f.has_attr("/", kModelForm)) m.model_form = f.attr_string("/", kModelForm);
  // the range of log a: +-inf when the per-bin fits set no bound, never NaN
  if (f.has_attr("/", kLogAMin)) m.log_a_min = f.attr_double("/", kLogAMin);
  if (f.has_attr("/", kLogAMax)) m.log_a_max = f.attr_double("/", kLogAMax);
  if (!(m.log_a_min <= m.log_a_max))
    refuse(f, "attributes 'log_a_min' = " + number(m.log_a_min) + " and 'log_a_max' = " + number(m.log_a_max) +
                  " of '/': expected log_a_min <= log_a_max (either may be -inf or inf, neither NaN)");
  read_calibration(f, m, spelling);
  if (f.has_attr("/", "code_version")) m.code_version = f.attr_string("/", "code_version");
  if (f.has_attr("/", "created")) m.created = f.attr_string("/", "created");
  if (f.has_attr("/", "scene")) m.scene_toml = f.attr_string("/", "scene");
}

ParcelFit read_parcel_fit(const h5::File& f) {
  ParcelFit p;
  for (const auto& n : kParcelFitNumbers) p.*n.member = f.attr_double(kCCorr, n.name);  // NaN: the fit said so
  for (const char* key : {"dof", "applied", "rejected", "a_fitted", "decision", "k_interval", "a_interval", "runs"})
    require_attr(f, kCCorr, key);
  p.dof = f.attr_int(kCCorr, "dof");
  p.applied = f.attr_int(kCCorr, "applied") != 0;
  p.rejected = f.attr_int(kCCorr, "rejected") != 0;
  p.a_fitted = f.attr_int(kCCorr, "a_fitted") != 0;
  p.decision = f.attr_string(kCCorr, "decision");
  if (f.has_attr(kCCorr, "method")) p.method = f.attr_string(kCCorr, "method");
  p.k_interval = finite_attrs(f, kCCorr, "k_interval", 2);
  p.a_interval = finite_attrs(f, kCCorr, "a_interval", 2);
  p.runs = f.attr_strings(kCCorr, "runs");
  for (const auto& v : kParcelFitRuns) {
    p.*v.member = f.has_attr(kCCorr, v.name) ? f.attr_doubles(kCCorr, v.name) : std::vector<double>{};
    if ((p.*v.member).size() != p.runs.size())
      refuse(f, std::string("attribute '") + v.name + "' of '/c_corr' holds " + std::to_string((p.*v.member).size()) +
                    " values, expected " + std::to_string(p.runs.size()) + " (one per entry of 'runs')");
  }
  return p;
}

M::CCorr read_c_corr(const h5::File& f) {
  require_group(f, kCCorr);
  M::CCorr c;
  c.a = finite_attr(f, kCCorr, "a");
  c.k = finite_attr(f, kCCorr, "k");
  c.source = f.attr_string(kCCorr, "source");
  if (f.has_attr(kCCorr, "fitted")) c.fitted = f.attr_int(kCCorr, "fitted") != 0;
  if (f.has_attr(kCCorr, "a_fit")) c.parcel_fit = read_parcel_fit(f);
  return c;
}

/// The 1-D float datasets of a group, all of one length: the first's, or `n` when given.
template <class S, std::size_t K>
void read_columns(const h5::File& f, const char* group, const Vec<S> (&table)[K], S& out, Finite finite,
                  std::uint64_t& n) {
  for (const auto& v : table) {
    const std::string name = child(group, v.name);
    out.*v.member = read_doubles(f, name, {n}, finite,
                                 n == kAnyExtent ? "" : "the length of the group's other datasets");
    n = (out.*v.member).size();
  }
}
template <class S, std::size_t K>
void read_columns(const h5::File& f, const char* group, const Ints<S> (&table)[K], S& out, std::uint64_t n) {
  for (const auto& v : table) out.*v.member = read_ints(f, child(group, v.name), {n}, "the length of the group's other datasets");
}

std::optional<Bands> read_bands(const h5::File& f) {
  if (!f.exists(kBands)) return std::nullopt;
  Bands b;
  if (f.has_attr(kBands, "replicates")) b.replicates = f.attr_int(kBands, "replicates");
  if (f.has_attr(kBands, "seed")) b.seed = f.attr_int(kBands, "seed");
  if (f.has_attr(kBands, "confidence")) b.confidence = finite_attr(f, kBands, "confidence");
  if (f.has_attr(kBands, "resampling")) b.resampling = f.attr_string(kBands, "resampling");
  b.phi = read_doubles(f, "/bands/phi", {kAnyExtent}, Finite::Everywhere);
  b.F = read_doubles(f, "/bands/F", {kAnyExtent}, Finite::Everywhere);
  const std::uint64_t np = b.phi.size();
  for (const auto& v : kBandCurves)
    if (v.member != &Bands::phi && v.member != &Bands::F)
      b.*v.member = read_doubles(f, child(kBands, v.name), {np}, Finite::Not, "len(/bands/phi)");
  for (const auto& v : kBandSurfaces)
    b.*v.member = read_doubles(f, child(kBands, v.name), {b.F.size(), np}, Finite::Not,
                               "(len(/bands/F), len(/bands/phi))");
  return b;
}

std::optional<Bins> read_bins(const h5::File& f) {
  if (!f.exists(kBins)) return std::nullopt;
  Bins b;
  std::uint64_t n = kAnyExtent;
  read_columns(f, kBins, kBinNumbers, b, Finite::Not, n);
  read_columns(f, kBins, kBinFlags, b, n);
  return b;
}

std::optional<M::Data> read_data(const h5::File& f) {
  if (!f.exists(kData)) return std::nullopt;
  M::Data d;
  d.F = read_doubles(f, "/data/F", {kAnyExtent}, Finite::Everywhere);
  d.phi = read_doubles(f, "/data/phi", {kAnyExtent}, Finite::Not);
  const std::string shape = "(len(/data/F), len(/data/phi))";
  d.H = read_doubles(f, "/data/H", {d.F.size(), d.phi.size()}, Finite::Not, shape);
  d.H_sigma = read_doubles(f, "/data/H_sigma", {d.F.size(), d.phi.size()}, Finite::Not, shape);
  d.fitted = read_ints(f, "/data/fitted", {d.F.size()}, "len(/data/F)");
  if (f.has_attr(kData, "series")) d.series = f.attr_strings(kData, "series");
  if (d.series.size() != d.F.size())
    refuse(f, "attribute 'series' of '/data' holds " + std::to_string(d.series.size()) + " names, expected " +
                  std::to_string(d.F.size()) + " (len(/data/F))");
  return d;
}

std::optional<Diagnostics> read_diagnostics(const h5::File& f) {
  if (!f.exists(kDiagnostics)) return std::nullopt;
  Diagnostics d;
  const char* g = kDiagnostics;
  for (const auto& n : kDiagnosticInts)
    if (f.has_attr(g, n.name)) d.*n.member = f.attr_int(g, n.name);
  for (const auto& n : kDiagnosticNumbers)
    if (f.has_attr(g, n.name)) d.*n.member = f.attr_double(g, n.name);  // NaN allowed (cv with one run)
  if (f.exists("/diagnostics/width_exponent_grid")) {
    d.width_exponent_grid = read_doubles(f, "/diagnostics/width_exponent_grid", {kAnyExtent}, Finite::Everywhere);
    d.width_exponent_chi2 = read_doubles(f, "/diagnostics/width_exponent_chi2", {d.width_exponent_grid.size()},
                                         Finite::Not, "len(/diagnostics/width_exponent_grid)");
    if (f.has_attr(g, "width_exponent_chi2_per_dof"))
      d.width_exponent_chi2_per_dof = f.attr_double(g, "width_exponent_chi2_per_dof");
  }
  if (f.has_attr(g, "residual_files")) d.residual_files = f.attr_strings(g, "residual_files");
  if (f.has_attr(g, "residual_groups")) d.residual_groups = f.attr_strings(g, "residual_groups");
  if (f.exists("/diagnostics/residual_F")) {
    std::uint64_t n = kAnyExtent;
    read_columns(f, g, kResidualNumbers, d, Finite::Not, n);
    d.residual_points = read_ints(f, "/diagnostics/residual_points", {n}, "len(/diagnostics/residual_F)");
  }
  if (f.exists("/diagnostics/cv_run")) {
    d.cv_run = read_ints(f, "/diagnostics/cv_run", {kAnyExtent});
    std::uint64_t n = d.cv_run.size();
    read_columns(f, g, kCrossValidationNumbers, d, Finite::Not, n);
    d.cv_points = read_ints(f, "/diagnostics/cv_points", {n}, "len(/diagnostics/cv_run)");
    if (f.has_attr(g, "cv_files")) d.cv_files = f.attr_strings(g, "cv_files");
  }
  return d;
}

std::optional<Table> read_table(const h5::File& f) {
  if (!f.exists(kTable)) return std::nullopt;
  Table t;
  std::uint64_t n = kAnyExtent;
  read_columns(f, kTable, kTableColumns, t, Finite::Everywhere, n);
  if (f.has_attr(kTable, "source_group")) t.source_group = f.attr_string(kTable, "source_group");
  if (f.has_attr(kTable, "min_count")) t.min_count = f.attr_int(kTable, "min_count");
  return t;
}

/// `/drift_table`: required with curves = drift_table (and read only then). phi and slip finite, strictly
/// increasing, at least one each; H finite of shape (len(phi), len(slip)), the sums of that shape, count and filled
/// int64 of that shape (count >= 0, filled in {0, 1, 2, 3}), phi_only_H of len(phi).
std::optional<Drift> read_drift_table(const h5::File& f, const M& m) {
  if (m.curves != ModelCurves::DriftTable) return std::nullopt;
  require_group(f, kDriftTable);
  Drift t;
  auto axis = [&](const char* name) {
    const std::string path = child(kDriftTable, name);
    std::vector<double> x = read_doubles(f, path, {kAnyExtent}, Finite::Everywhere);
    if (x.empty() || std::adjacent_find(x.begin(), x.end(), std::greater_equal<>()) != x.end())
      refuse(f, "dataset '" + path + "' holds " + std::to_string(x.size()) +
                    " values, expected at least one, strictly increasing (the table's bin centres)");
    return x;
  };
  t.phi = axis("phi");
  t.slip = axis("slip");
  const std::vector<std::uint64_t> shape{t.phi.size(), t.slip.size()};
  const std::string why = "(len(/drift_table/phi), len(/drift_table/slip))";
  t.H = read_doubles(f, child(kDriftTable, "H"), shape, Finite::Everywhere, why);
  for (const auto& v : kDriftSums)
    if (f.exists(child(kDriftTable, v.name))) t.*v.member = read_doubles(f, child(kDriftTable, v.name), shape, Finite::Not, why);
  for (const auto& v : kDriftInts) t.*v.member = read_ints(f, child(kDriftTable, v.name), shape, why);
  for (std::size_t k = 0; k < t.count.size(); ++k) {
    if (t.count[k] < 0)
      refuse(f, "dataset '/drift_table/count' holds " + std::to_string(t.count[k]) + ", expected counts >= 0");
    if (t.filled[k] < 0 || t.filled[k] > 3)
      refuse(f, "dataset '/drift_table/filled' holds " + std::to_string(t.filled[k]) +
                    ", expected 0 (measured), 1 (nearest slip bin) or 2 (phi-only H_grid)");
  }
  if (f.exists(child(kDriftTable, "phi_only_H")))
    t.phi_only_H = read_doubles(f, child(kDriftTable, "phi_only_H"), {t.phi.size()}, Finite::Not, "len(/drift_table/phi)");
  if (f.has_attr(kDriftTable, "source_group")) t.source_group = f.attr_string(kDriftTable, "source_group");
  if (f.has_attr(kDriftTable, "fill_rule")) t.fill_rule = f.attr_string(kDriftTable, "fill_rule");
  if (f.has_attr(kDriftTable, "min_count")) t.min_count = f.attr_int(kDriftTable, "min_count");
  if (f.has_attr(kDriftTable, "min_alignment")) t.min_alignment = f.attr_double(kDriftTable, "min_alignment");
  if (f.has_attr(kDriftTable, "phi_bin_width")) t.phi_bin_width = f.attr_double(kDriftTable, "phi_bin_width");
  if (f.has_attr(kDriftTable, "slip_bin_width")) t.slip_bin_width = f.attr_double(kDriftTable, "slip_bin_width");
  if (f.has_attr(kDriftTable, "slip_unit") && f.attr_string(kDriftTable, "slip_unit") != "u_t")
    refuse(f, "attribute 'slip_unit' of '/drift_table' is \"" + f.attr_string(kDriftTable, "slip_unit") +
                  "\", expected \"u_t\"");
  return t;
}

void read_sources_and_provenance(const h5::File& f, M& m) {
  if (f.has_attr(kSources, "files")) m.source_files = f.attr_strings(kSources, "files");
  if (f.has_attr(kSources, "checksums")) m.source_checksums = f.attr_strings(kSources, "checksums");
  if (f.has_attr(kSources, "pooled_runs")) {  // absent (files written before it): the files side by side
    const std::int64_t pooled = f.attr_int(kSources, "pooled_runs");
    if (pooled != 0 && pooled != 1)
      refuse(f, "attribute 'pooled_runs' of '/sources' is " + std::to_string(pooled) + ", expected 0 or 1");
    m.sources_pooled = pooled == 1;
  }
  if (f.exists(kProvenance))
    for (const char* key : kProvenanceKeys)
      if (f.has_attr(kProvenance, key)) m.provenance.emplace_back(key, f.attr_string(kProvenance, key));
}

}  // namespace

const char* to_string(ModelCurves curves) {
  switch (curves) {
    case ModelCurves::Table: return "table";
    case ModelCurves::DriftTable: return "drift_table";
    case ModelCurves::Splines: break;
  }
  return "splines";
}

void write_drag_model(const std::string& path, const Scene& scene, const DragModelFile& m) {
  h5::write_atomically(path, MPI_COMM_SELF, [&](h5::File& f) {
    write_common(f, kDragModel, scene);
    write_root(f, m);
    write_spline(f, kH, m.h);
    write_spline(f, kLogA, m.log_a);
    if (m.table) write_table(f, *m.table);
    if (m.drift_table) write_drift_table(f, *m.drift_table);
    write_c_corr(f, m.c_corr);
    if (m.bands) write_bands(f, *m.bands);
    if (m.bins) write_bins(f, *m.bins);
    if (m.data) write_data(f, *m.data);
    if (m.diagnostics) write_diagnostics(f, *m.diagnostics);
    write_sources(f, m);
  });
}

void write_c_corr_copy(const std::string& model_path, const std::string& output_path, const DragModelFile::CCorr& c) {
  h5::update_copy_atomically(model_path, output_path, [&](h5::File& f) { write_c_corr_attributes(f, c); });
}

DragModelFile read_drag_model(const std::string& path) {
  h5::File f = h5::File::open_read(path, MPI_COMM_SELF);
  M m;
  m.version = check_format(f, kDragModel);
  read_root(f, m);
  m.h = read_spline(f, kH);
  m.log_a = read_spline(f, kLogA);
  if (m.curves != ModelCurves::Splines && m.h.order != 2)
    refuse(f, "attribute 'order' of '/h' is " + std::to_string(m.h.order) + ", expected 2 with curves = \"" +
                  to_string(m.curves) + "\" (piecewise linear)");
  m.c_corr = read_c_corr(f);
  m.bands = read_bands(f);
  m.bins = read_bins(f);
  m.data = read_data(f);
  m.diagnostics = read_diagnostics(f);
  m.table = read_table(f);
  m.drift_table = read_drift_table(f, m);
  read_sources_and_provenance(f, m);
  return m;
}

}  // namespace cgd::schema
