#pragma once
// The series file (cgd_format "series", series.h5 of a run directory, docs/schema-run.md "Series"): its one
// home. The time-series table (Series, any columns; one write, one validating read), the names of its root
// attributes and of the columns a run of cgd-generate / cgd-coarse writes (RunSeriesRow, in the order
// declare_run_columns gives), each spelled once below. Readers (the coarse summary, tools/) find a column by
// its name.
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "core/scene.hpp"
#include "core/schema/common.hpp"

namespace cgd::schema::names {

// series: root attributes (and each column's `unit`, names::kUnit)
inline constexpr const char* kColumns = "columns";    // the column names, in file order; the first is time
inline constexpr const char* kRows = "rows";          // the rows of every column
inline constexpr const char* kWarnings = "warnings";  // the run's warnings (optional)

// series: the columns of a run (datasets /<name>, (rows) or (rows, 3)), in file order
inline constexpr const char* kColTime = "time";
inline constexpr const char* kColStep = "step";
inline constexpr const char* kColSolidsFraction = "solids_fraction";
inline constexpr const char* kColSlipVelocity = "slip_velocity";
inline constexpr const char* kColFluidVelocityMean = "fluid_velocity_mean";
inline constexpr const char* kColParticleVelocityMean = "particle_velocity_mean";
inline constexpr const char* kColKineticEnergy = "kinetic_energy";
inline constexpr const char* kColRotationalEnergy = "rotational_energy";
inline constexpr const char* kColContactEnergy = "contact_energy";
inline constexpr const char* kColMomentum = "momentum";
inline constexpr const char* kColContactsPerParticle = "contacts_per_particle";
inline constexpr const char* kColMaxOverlapRel = "max_overlap_rel";
inline constexpr const char* kColNeighborRebuilds = "neighbor_rebuilds";
inline constexpr const char* kColWallSeconds = "wall_seconds";
inline constexpr const char* kColDtFluid = "dt_fluid";
inline constexpr const char* kColFluidKineticEnergy = "fluid_kinetic_energy";
inline constexpr const char* kColContinuityResidualRel = "continuity_residual_rel";
inline constexpr const char* kColPressureIterations = "pressure_iterations";
inline constexpr const char* kColMaxSolidsFraction = "max_solids_fraction";
inline constexpr const char* kColFlooredCells = "floored_cells";

}  // namespace cgd::schema::names

namespace cgd::schema {

/// Time series kept on every rank (identical rows, values already reduced), written whole and
/// atomically; read back on restart and truncated to the checkpoint time.
class Series {
 public:
  /// Declare a column before the first row: `width` values per row (e.g. 3 for a vector), `unit` as text.
  void add_column(const std::string& name, int width, const std::string& unit);
  /// One row: the concatenation of every column's values, in declaration order; column 0 is time.
  void append(const std::vector<double>& row);
  void truncate_after(double time_s);  // drop rows with time > time_s (restart)
  std::size_t rows() const { return rows_; }
  int row_width() const;
  const std::vector<double>& column(const std::string& name) const;  // rows x width, flattened
  void write(const std::string& path, MPI_Comm comm, const Scene& scene) const;
  /// Read and validate a series file written by `write` (any rank): the format and version, `columns`
  /// naming `time` first, every listed column a dataset of (rows) or (rows, width), `rows` rows each as the
  /// attribute says, times finite and non-decreasing. InputError naming the file, the dataset or attribute,
  /// what was found and what was expected.
  static Series read(const std::string& path, MPI_Comm comm);
  /// Warnings of the run (each once), written as the root attribute `warnings` (string list).
  void add_warning(const std::string& text) { warnings_.push_back(text); }
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  std::vector<std::string> warnings_;
  struct Column {
    std::string name, unit;
    int width = 1;
    std::vector<double> values;
  };
  std::vector<Column> columns_;
  std::size_t rows_ = 0;
};

/// What a run's series holds, fixed for the whole run (and its restarts): which optional columns exist
/// and the names of the per-phase timers (one column `time_<phase>_s` each).
struct RunSeriesLayout {
  // the scene has a [fluid] section: slip and fluid velocity (u = 0 when quiescent)
  bool fluid_scene = false;
  bool solves_fluid = false;             // a fluid is solved: the per-fluid-step columns (dt_fluid, ...)
  std::vector<std::string> phase_names;  // dataset-safe names ("force_integrate", "fluid_pressure", ...)
};

/// One row of a run's series, every value already reduced over the ranks (identical on every rank).
/// Fields that the layout does not call for are ignored.
struct RunSeriesRow {
  double time_s = 0;
  std::int64_t step = 0;
  double solids_fraction = 0;         // <phi>, from the particle count and the box
  Vec3 slip_velocity_m_s{};           // <eps u>/<eps> - <phi v>/<phi> (fluid scenes)
  Vec3 fluid_velocity_mean_m_s{};     // <eps u>/<eps> (fluid scenes)
  Vec3 particle_velocity_mean_m_s{};  // <phi v>/<phi>
  double kinetic_energy_J = 0;        // translational, particles
  double rotational_energy_J = 0;
  double contact_energy_J = 0;  // elastic energy stored in the springs
  Vec3 momentum_kg_m_s{};
  double contacts_per_particle = 0;
  double max_overlap_rel = 0;  // largest overlap / diameter
  std::int64_t neighbor_rebuilds = 0;
  double wall_seconds = 0;  // since the run (not the session) started
  // solves_fluid only
  double dt_fluid_s = 0;  // the fluid step that ended at this row
  double fluid_kinetic_energy_J = 0;
  double continuity_residual_rel = 0;
  std::int64_t pressure_iterations = 0;
  double max_solids_fraction = 0;     // largest cell phi
  std::int64_t floored_cells = 0;     // cells at the void-fraction floor
  std::vector<double> phase_seconds;  // per phase of the layout, run totals
};

/// A phase timer's column, "time_<phase>_s" ("time_force_integrate_s"): the run's total seconds in the phase.
std::string phase_column(const std::string& phase);

/// Declares the run columns of `layout` on an empty series, in file order (docs/schema-run.md).
void declare_run_columns(Series& series, const RunSeriesLayout& layout);

/// Appends one row in the order declare_run_columns declared. Throws std::invalid_argument when the
/// row's phase count does not match the layout.
void append_run_row(Series& series, const RunSeriesLayout& layout, const RunSeriesRow& row);

}  // namespace cgd::schema
