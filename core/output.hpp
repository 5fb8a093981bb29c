#pragma once
// The one place that knows the file schema (ARCHITECTURE.md "Files", docs/schema-run.md).
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "core/h5.hpp"
#include "core/scene.hpp"
#include "core/schema/check.hpp"  // Format
#include "core/series.hpp"  // schema::Series, the run's series.h5

namespace cgd::schema {

/// Root attributes every cgd file carries: cgd_format, cgd_format_version (format's row in
/// core/schema/check.hpp), code_version, created
/// (ISO 8601 UTC), scene (the effective scene as TOML text); and group /params with every physical
/// and derived parameter of the scene as attributes (SI, names with units). Collective.
void write_common(h5::File& file, const Format& format, const Scene& scene);

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
