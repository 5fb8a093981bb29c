#pragma once
// The one place that knows the file schema (design.md, "Files (HDF5 schema, version 1)").
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "core/h5.hpp"
#include "core/scene.hpp"

namespace cgd::schema {

inline constexpr std::int64_t kFormatVersion = 1;

/// Root attributes every cgd file carries: cgd_format, cgd_format_version, code_version, created
/// (ISO 8601 UTC), scene (the effective scene as TOML text); and group /params with every physical
/// and derived parameter of the scene as attributes (SI, names with units). Collective.
void write_common(h5::File& file, const char* format, const Scene& scene);

/// This rank's owned particles as views (SoA, vectors interleaved xyz). Optional fields are nullptr
/// when the run does not simulate them (then the dataset is absent from the file).
struct ParticleFields {
  std::int64_t count = 0;
  const std::int64_t* id = nullptr;
  const double* position = nullptr;          // count x 3, m
  const double* velocity = nullptr;          // count x 3, m/s
  const double* angular_velocity = nullptr;  // count x 3, rad/s (rotation simulated)
  const double* diameter = nullptr;          // count, m
  const double* drag_coefficient = nullptr;  // count, beta_p,i (kg m^-3 s^-1)
  const double* fluid_velocity = nullptr;    // count x 3, u at the particle
  const double* pressure_gradient = nullptr; // count x 3, grad p at the particle, mean removed
  Vec3 pressure_gradient_mean{};             // the removed mean (attribute)
};

/// This rank's slab of the fluid grid: cells [y_offset, y_offset + y_count) along y, all of x and z.
/// Arrays are in file order (z, y_local, x), x fastest; velocity has a trailing 3.
struct FluidFields {
  std::array<int, 3> cells{};   // global (n_x, n_y, n_z)
  Vec3 spacing_m{};
  Vec3 origin_m{};
  int y_offset = 0, y_count = 0;
  const double* void_fraction = nullptr;
  const double* velocity = nullptr;
  const double* pressure = nullptr;
  /// Cell-centred eps u (trailing 3): the mean of the two faces' fluxes eps_f u_f, so that its sum
  /// over the cells equals the solver's sum over the faces (the series' <eps u>) exactly. Optional.
  const double* eps_velocity = nullptr;
};

/// Write a snapshot file atomically (attributes time, step; /params; /particles; /fluid if given).
void write_snapshot(const std::string& path, MPI_Comm comm, const Scene& scene, double time_s, std::int64_t step,
                    const ParticleFields& particles, const FluidFields* fluid = nullptr);

/// Time series kept on every rank (identical rows, values already reduced), written whole and
/// atomically; read back on restart and truncated to the checkpoint time.
class Series {
 public:
  /// Declare a column before the first row: `width` values per row (e.g. 3 for a vector), `unit` as text.
  void add_column(const std::string& name, int width, const std::string& unit);
  /// One row: the concatenation of every column's values, in declaration order; column 0 is time.
  void append(const std::vector<double>& row);
  void truncate_after(double time_s);       // drop rows with time > time_s (restart)
  std::size_t rows() const { return rows_; }
  int row_width() const;
  const std::vector<double>& column(const std::string& name) const;  // rows x width, flattened
  void write(const std::string& path, MPI_Comm comm, const Scene& scene) const;
  /// Read a series file written by `write` (any rank; InputError if unreadable).
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

/// One entry of run.xmf's temporal collection.
struct XdmfFrame {
  std::string snapshot_file;  // relative to the run directory, e.g. "snapshots/snap_000000100.h5"
  double time_s = 0;
  std::int64_t particle_count = 0;
  bool has_angular_velocity = false;
  bool has_fluid = false;
  std::array<int, 3> cells{};  // (n_x, n_y, n_z) when has_fluid
  Vec3 spacing_m{}, origin_m{};
};

/// (Re)write `run_dir/run.xmf` (XDMF 3) atomically: a temporal collection whose frames hold the
/// particles as a polyvertex grid with velocity, diameter, id (and angular velocity) and, when
/// present, the fluid as a 3D CoRectMesh with cell data (void_fraction, velocity, pressure).
/// Rank 0 only (not collective).
void write_xdmf(const std::string& run_dir, const std::vector<XdmfFrame>& frames);

}  // namespace cgd::schema
