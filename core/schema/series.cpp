// The series file (docs/schema-run.md "Series"): the time-series table, its write and validating read, and
// a run's columns. The names are core/schema/series.hpp's.
#include "core/schema/series.hpp"

#include <stdexcept>

#include "core/error.hpp"
#include "core/schema/check.hpp"

namespace cgd::schema {

using namespace names;

// ---- Series ----------------------------------------------------------------------------------------------

void Series::add_column(const std::string& name, int width, const std::string& unit) {
  if (rows_ > 0) throw std::logic_error("Series::add_column('" + name + "') after rows were appended");
  if (name.empty() || name.find('/') != std::string::npos || width < 1)
    throw std::invalid_argument("Series::add_column: bad column '" + name + "' of width " +
                                std::to_string(width));
  for (const Column& c : columns_)
    if (c.name == name)
      throw std::invalid_argument("Series::add_column: column '" + name + "' declared twice");
  columns_.push_back(Column{name, unit, width, {}});
}

int Series::row_width() const {
  int width = 0;
  for (const Column& c : columns_) width += c.width;
  return width;
}

void Series::append(const std::vector<double>& row) {
  if (columns_.empty()) throw std::logic_error("Series::append before any column was declared");
  if (static_cast<int>(row.size()) != row_width())
    throw std::invalid_argument("Series::append: row of " + std::to_string(row.size()) +
                                " values, expected " + std::to_string(row_width()));
  auto it = row.begin();
  for (Column& c : columns_) {
    c.values.insert(c.values.end(), it, it + c.width);
    it += c.width;
  }
  ++rows_;
}

void Series::truncate_after(double time_s) {
  if (columns_.empty() || rows_ == 0) return;
  const std::vector<double>& time = columns_.front().values;  // column 0 is time (width 1)
  const int time_width = columns_.front().width;
  std::vector<bool> keep(rows_);
  std::size_t kept = 0;
  for (std::size_t r = 0; r < rows_; ++r) kept += (keep[r] = time[r * time_width] <= time_s);
  for (Column& c : columns_) {
    std::vector<double> values;
    values.reserve(kept * c.width);
    for (std::size_t r = 0; r < rows_; ++r)
      if (keep[r])
        values.insert(values.end(), c.values.begin() + r * c.width, c.values.begin() + (r + 1) * c.width);
    c.values = std::move(values);
  }
  rows_ = kept;
}

const std::vector<double>& Series::column(const std::string& name) const {
  std::string names;
  for (const Column& c : columns_) {
    if (c.name == name) return c.values;
    names += (names.empty() ? "" : ", ") + c.name;
  }
  throw InputError("series: no column '" + name + "' (columns: " + names + ")");
}

void Series::write(const std::string& path, MPI_Comm comm, const Scene& scene) const {
  h5::write_atomically(path, comm, [&](h5::File& f) {
    write_common(f, kSeries, scene);
    std::vector<std::string> names;
    for (const Column& c : columns_) names.push_back(c.name);
    f.set_attr(kRoot, kColumns, names);
    f.set_attr(kRoot, kRows, static_cast<std::int64_t>(rows_));
    if (!warnings_.empty()) f.set_attr(kRoot, kWarnings, warnings_);
    for (const Column& c : columns_) {
      const std::string dataset = "/" + c.name;
      std::vector<std::uint64_t> dims{rows_};
      if (c.width > 1) dims.push_back(static_cast<std::uint64_t>(c.width));
      f.write_replicated(dataset, c.values, dims);
      f.set_attr(dataset, kUnit, c.unit);
    }
  });
}

Series Series::read(const std::string& path, MPI_Comm comm) {
  h5::File f = h5::File::open_read(path, comm);
  schema::check_format(f, kSeries);
  Series s;
  if (f.has_attr(kRoot, kWarnings)) s.warnings_ = f.attr_strings(kRoot, kWarnings);
  const std::vector<std::string> names = f.attr_strings(kRoot, kColumns);
  if (names.empty() || names.front() != kColTime)
    throw InputError(path + ": attribute '" + kColumns + "' of '/' " +
                     (names.empty() ? std::string("is empty") : "starts with '" + names.front() + "'") +
                     ", expected the column '" + kColTime + "' first");
  for (const std::string& name : names) {
    const std::string dataset = "/" + name;
    if (!f.exists(dataset))
      throw InputError(path + ": no dataset '" + dataset + "', expected the column the attribute '" + kColumns + "' lists");
    const std::vector<std::uint64_t> dims = f.dims(dataset);
    if (dims.empty() || dims.size() > 2)
      throw InputError(path + ": dataset '" + dataset + "' has shape " + shape_text(dims) +
                       ", expected a series column of shape (rows,) or (rows, width)");
    Column c;
    c.name = name;
    c.width = dims.size() == 2 ? static_cast<int>(dims[1]) : 1;
    c.unit = f.has_attr(dataset, kUnit) ? f.attr_string(dataset, kUnit) : "";
    // the time column orders the rows (a restart cuts the series back by it): finite and non-decreasing
    c.values = read_doubles(f, dataset, dims, s.columns_.empty() ? Finite::Everywhere : Finite::Not);
    if (s.columns_.empty()) {
      s.rows_ = dims[0];
      for (std::size_t r = 1; r < c.values.size(); ++r)
        if (c.values[r] < c.values[r - 1])
          throw InputError(path + ": dataset '/" + kColTime + "' decreases at row " + std::to_string(r) + " (" +
                           std::to_string(c.values[r - 1]) + " then " + std::to_string(c.values[r]) +
                           "), expected non-decreasing times");
    } else if (dims[0] != s.rows_) {
      throw InputError(path + ": dataset '" + dataset + "' has " + std::to_string(dims[0]) + " rows, expected " +
                       std::to_string(s.rows_) + " (the rows of '/" + kColTime + "')");
    }
    s.columns_.push_back(std::move(c));
  }
  if (const std::int64_t rows = f.attr_int(kRoot, kRows); rows != static_cast<std::int64_t>(s.rows_))
    throw InputError(path + ": attribute '" + kRows + "' of '/' is " + std::to_string(rows) + ", expected " +
                     std::to_string(s.rows_) + " (the rows of '/" + kColTime + "')");
  f.close();
  return s;
}

// ---- a run's columns -------------------------------------------------------------------------------

std::string phase_column(const std::string& phase) {
  return "time_" + phase + "_s";
}

void declare_run_columns(Series& series, const RunSeriesLayout& layout) {
  series.add_column(kColTime, 1, "s");
  series.add_column(kColStep, 1, "1");
  series.add_column(kColSolidsFraction, 1, "1");
  if (layout.fluid_scene) {
    series.add_column(kColSlipVelocity, 3, "m/s");
    series.add_column(kColFluidVelocityMean, 3, "m/s");
  }
  series.add_column(kColParticleVelocityMean, 3, "m/s");
  series.add_column(kColKineticEnergy, 1, "J");
  series.add_column(kColRotationalEnergy, 1, "J");
  series.add_column(kColContactEnergy, 1, "J");
  series.add_column(kColMomentum, 3, "kg m/s");
  series.add_column(kColContactsPerParticle, 1, "1");
  series.add_column(kColMaxOverlapRel, 1, "1");
  series.add_column(kColNeighborRebuilds, 1, "1");
  series.add_column(kColWallSeconds, 1, "s");
  if (layout.solves_fluid) {
    series.add_column(kColDtFluid, 1, "s");
    series.add_column(kColFluidKineticEnergy, 1, "J");
    series.add_column(kColContinuityResidualRel, 1, "1");
    series.add_column(kColPressureIterations, 1, "1");
    series.add_column(kColMaxSolidsFraction, 1, "1");
    series.add_column(kColFlooredCells, 1, "1");
  }
  for (const std::string& name : layout.phase_names) series.add_column(phase_column(name), 1, "s");
}

void append_run_row(Series& series, const RunSeriesLayout& layout, const RunSeriesRow& r) {
  if (r.phase_seconds.size() != layout.phase_names.size())
    throw std::invalid_argument("append_run_row: " + std::to_string(r.phase_seconds.size()) +
                                " phase times for " + std::to_string(layout.phase_names.size()) + " phases");
  std::vector<double> row{r.time_s, static_cast<double>(r.step), r.solids_fraction};
  const auto vec = [&](const Vec3& v) { row.insert(row.end(), v.begin(), v.end()); };
  if (layout.fluid_scene) {
    vec(r.slip_velocity_m_s);
    vec(r.fluid_velocity_mean_m_s);
  }
  vec(r.particle_velocity_mean_m_s);
  row.push_back(r.kinetic_energy_J);
  row.push_back(r.rotational_energy_J);
  row.push_back(r.contact_energy_J);
  vec(r.momentum_kg_m_s);
  row.push_back(r.contacts_per_particle);
  row.push_back(r.max_overlap_rel);
  row.push_back(static_cast<double>(r.neighbor_rebuilds));
  row.push_back(r.wall_seconds);
  if (layout.solves_fluid) {
    row.push_back(r.dt_fluid_s);
    row.push_back(r.fluid_kinetic_energy_J);
    row.push_back(r.continuity_residual_rel);
    row.push_back(static_cast<double>(r.pressure_iterations));
    row.push_back(r.max_solids_fraction);
    row.push_back(static_cast<double>(r.floored_cells));
  }
  row.insert(row.end(), r.phase_seconds.begin(), r.phase_seconds.end());
  series.append(row);
}

}  // namespace cgd::schema
