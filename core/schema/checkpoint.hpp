#pragma once
// The checkpoint file (cgd_format "checkpoint", checkpoint.h5 of a run directory, docs/schema-run.md
// "Checkpoint"): its one home. Everything a restart needs to continue a run bit for bit -- the DEM state
// (unwrapped positions, leapfrog velocities, the contact histories keyed by partner id), the neighbour-list
// bookkeeping, the fluid state and the run's own bookkeeping (wall time, phase timers, snapshot frames).
// The names (each spelled once, below; the particles' id, position, velocity and spin and the root's step
// and time are a snapshot's, core/schema/snapshot.hpp), the plain structs the engine (sim/run_checkpoint.cpp)
// fills and consumes, one write and one validating read (Reader).
#include <mpi.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/h5.hpp"
#include "core/scene.hpp"
#include "core/schema/snapshot.hpp"  // the names shared with snapshots

namespace cgd::checkpoint::names {

// the root, /particles id, position, velocity and angular_velocity, /fluid, step and time: a snapshot's
using schema::names::kAngularVelocity;
using schema::names::kFluid;
using schema::names::kId;
using schema::names::kParticles;
using schema::names::kPosition;
using schema::names::kRoot;
using schema::names::kStep;
using schema::names::kTime;
using schema::names::kVelocity;
inline constexpr const char* kContactCount = "/particles/contact_count";
inline constexpr const char* kListAnchor = "/particles/list_anchor";  // version 3
inline constexpr const char* kContacts = "/contacts";
inline constexpr const char* kPartner = "/contacts/partner";
inline constexpr const char* kSpring = "/contacts/spring";
inline constexpr const char* kDtPrevious = "dt_previous";  // of /fluid
inline constexpr const char* kFluidSteps = "steps";        // of /fluid
inline constexpr const char* kRebuildDue = "rebuild_due";
inline constexpr const char* kSkin = "skin";
inline constexpr const char* kLastSortStep = "last_sort_step";
inline constexpr const char* kRanks = "ranks";
inline constexpr const char* kRankParticleCounts = "rank_particle_counts";
inline constexpr const char* kRankContactCounts = "rank_contact_counts";
inline constexpr const char* kWallSeconds = "wall_seconds";
inline constexpr const char* kPhaseSeconds = "phase_seconds";
inline constexpr const char* kFrameSteps = "frame_steps";
inline constexpr const char* kFrameTimes = "frame_times";
inline constexpr const char* kFrameCounts = "frame_counts";
inline constexpr const char* kPlacementMethod = "placement_method";
inline constexpr const char* kNeighborRebuilds = "neighbor_rebuilds";
inline constexpr const char* kSlabBounds = "slab_bounds";  // version 4

}  // namespace cgd::checkpoint::names

namespace cgd::checkpoint {

/// A snapshot written so far (run.xmf is rebuilt from these after a restart).
struct Frame {
  std::int64_t step = 0;
  double time_s = 0;
  std::int64_t particle_count = 0;
};

/// The run's bookkeeping at the checkpoint step (root attributes).
struct RunState {
  std::int64_t step = 0;
  double time_s = 0;
  bool rebuild_due = false;         // the neighbour list must be rebuilt before the next step
  double skin_m = 0;                // the last build's largest pair skin (0: not stored)
  std::int64_t last_sort_step = 0;  // step of the last reordering by cell
  std::int64_t neighbor_rebuilds = 0;
  // the lower y bound of every rank's DEM slab in force, m (ranks values; the slabs move at list rebuilds, so a
  // restart between rebuilds at the same rank count needs them); empty: not stored (before version 4; the
  // restart then rebuilds the list at its first step)
  std::vector<double> slab_bounds;
  double wall_seconds = 0;            // wall time of the whole run so far (all sessions)
  std::vector<double> phase_seconds;  // per phase timer, the whole run so far (DEM phases first)
  std::vector<Frame> frames;
  std::string placement_method;
};

/// This rank's owned particles and their contact records, as views (interleaved xyz vectors). The
/// contact records of particle i are rows [sum of contact_count[<i]], ...) of partner/spring.
struct ParticleRows {
  std::int64_t count = 0;
  const std::int64_t* id = nullptr;
  const double* position = nullptr;          // unwrapped, m
  const double* velocity = nullptr;          // leapfrog v_{n-1/2}, m/s
  const double* angular_velocity = nullptr;  // rad/s; nullptr when rotation is not simulated
  const std::int64_t* contact_count = nullptr;
  std::int64_t contact_rows = 0;
  const std::int64_t* partner = nullptr;  // partner's global id
  const double* spring = nullptr;         // tangential history spring (x 3), as seen from the particle
  const float* anchor = nullptr;          // neighbour-list anchor (x 4: position at the last build, reach), m
};

/// The fluid fields a bit-exact restart needs, by dataset name under /fluid, in this order. Each is
/// written as the rank's owned planes in grid order (y, z, x), concatenated over the ranks in y order:
/// the global (y, z, x) order, so any rank count reads it back.
inline constexpr std::array<const char*, 8> kFluidFieldNames = {
    "velocity_x",        "velocity_y",      "velocity_z",      "pressure",
    "void_fraction_old", "explicit_rate_x", "explicit_rate_y", "explicit_rate_z"};

/// This rank's fluid slab: `fields[k]` points at `cells` values of kFluidFieldNames[k].
struct FluidRows {
  double dt_previous_s = 0;  // the last fluid step (AB2 needs it)
  std::int64_t steps = 0;    // fluid steps done
  std::int64_t cells = 0;    // owned cells of this rank
  std::array<const double*, kFluidFieldNames.size()> fields{};
};

/// Writes `path` atomically (h5::write_atomically): the common root attributes and /params of `scene`,
/// `state`, every rank's particles (with the per-rank counts that let the same rank count read its own
/// rows back) and, when given, the fluid. Collective.
void write(const std::string& path, MPI_Comm comm, const Scene& scene, const RunState& state,
           const ParticleRows& particles, const FluidRows* fluid);

/// What a checkpoint says about its run without its state: the effective scene it was written with (TOML
/// text and name) and the rank count that wrote it. Opening checks the seal and the format (check_format),
/// so a damaged checkpoint is refused before a restart compares scenes. Collective.
struct Header {
  std::string scene_toml, scene_name;
  std::int64_t ranks = 1;
};
Header read_header(const std::string& path, MPI_Comm comm);

/// Particle rows read back (owning vectors, same meaning as ParticleRows).
struct ParticleData {
  std::vector<std::int64_t> id;
  std::vector<double> position, velocity, angular_velocity;  // angular_velocity empty without rotation
  std::vector<std::int64_t> contact_count;
  std::vector<std::int64_t> partner;
  std::vector<double> spring;
  std::vector<float> anchor;  // 4 per particle; empty from a checkpoint older than version 3
};

/// An open checkpoint, for reading (any rank count).
class Reader {
 public:
  /// Opens `path` (File::open_read checks its checksum seal first), reads the run state and validates the
  /// file (docs/schema-run.md "What the readers check"): the format and version, every attribute's type,
  /// finite times, per-rank counts that match the rank count, every particle array of N = the sum of
  /// rank_particle_counts rows (and 3 columns where it is a vector), M = the sum of rank_contact_counts
  /// contact records matching the particles' contact_count, ids and partners >= 0, finite positions, velocities,
  /// springs and fluid fields, the eight fluid fields of one length. InputError naming the file, the
  /// dataset or attribute, what was found and what was expected; every rank throws the same. Collective.
  Reader(const std::string& path, MPI_Comm comm);
  const RunState& state() const { return state_; }
  const std::string& path() const { return file_.path(); }
  /// Rank count of the run that wrote it, and its per-rank particle and contact-record counts.
  std::int64_t ranks() const { return ranks_; }
  const std::vector<std::int64_t>& rank_particle_counts() const { return particle_counts_; }
  const std::vector<std::int64_t>& rank_contact_counts() const { return contact_counts_; }
  bool has_angular_velocity() const;
  /// Particles [first, first + count) and contact records [contact_first, contact_first + contact_count).
  ParticleData particles(std::int64_t first, std::int64_t count, std::int64_t contact_first,
                         std::int64_t contact_count, bool rotation) const;
  bool has_fluid() const;
  /// Cells of each fluid field (0 without /fluid).
  std::int64_t fluid_cells() const { return fluid_cells_; }
  double fluid_dt_previous_s() const;
  std::int64_t fluid_steps() const;
  /// Cells [first, first + count) of kFluidFieldNames[field] in the global (y, z, x) order, into `out`.
  void read_fluid_field(std::size_t field, std::int64_t first, std::int64_t count, double* out) const;
  void close();

 private:
  h5::File file_;
  RunState state_;
  std::int64_t ranks_ = 1;
  std::vector<std::int64_t> particle_counts_, contact_counts_;
  std::int64_t fluid_cells_ = 0;
  std::int64_t version_ = 0;
  void scan_values(MPI_Comm comm, std::int64_t n, std::int64_t m) const;
};

}  // namespace cgd::checkpoint
