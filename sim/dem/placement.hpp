#pragma once
// Initial particle placement without overlap in a periodic box.
#include <mpi.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace cgd::dem {

struct Placement {
  std::vector<double> position;  // 3 per particle
  std::vector<double> velocity;  // 3 per particle
  std::string method;            // how it was placed, for the log and the files
  double min_gap_rel = 0;        // smallest surface gap / diameter found after placement
};

/// This rank's share of a placement (place_particles_distributed): global ids and their positions and
/// velocities, in no particular order; which rank holds which particle is not the run's slab layout
/// (the run's first rebuild migrates them).
struct LocalPlacement {
  std::vector<std::int64_t> id;
  std::vector<double> position;  // 3 per particle
  std::vector<double> velocity;  // 3 per particle
  std::string method;
  double min_gap_rel = 0;        // global
};

/// Place `count` spheres of diameter `d` at random without overlap, deterministic in `seed` and the
/// same for any number of ranks (so runs at any rank count start from the same state, bit for bit).
/// Collective; each rank holds about count/ranks particles at any time (no rank holds them all).
///
/// Random sequential addition (RSA) in fixed y-blocks of the box (their number depends on the box only:
/// about 8 diameters high, at most 256): blocks are filled in two or three colour phases so that blocks
/// filled at the same time never touch, each from its own random stream (seed, block) and against the
/// particles of the neighbouring blocks already filled; so the result does not depend on which rank
/// fills which block. Up to a solids fraction of 0.30 RSA places the spheres at their size (RSA jams
/// near 0.38 and slows down well before); denser packings start from RSA of smaller spheres at 0.25,
/// grown to the target diameter in a few stages of at most 6 % each by a frictionless, strongly damped
/// soft-sphere relaxation (this project's DEM, slab-parallel; its trajectories do not depend on the rank
/// count), which removes the overlaps; only the last stage relaxes them fully (residual 2e-4 of the
/// aimed diameter d (1 + 1e-3)), ending without overlap. Velocities: Gaussian with rms speed
/// `velocity_rms` (per component rms/sqrt(3)) from a random stream per particle id, zero total momentum.
LocalPlacement place_particles_distributed(MPI_Comm comm, const std::array<double, 3>& box_m, double d,
                                           std::int64_t count, double velocity_rms, std::uint64_t seed);

/// The same placement on one process, in id order (particle i at position[3 i .. 3 i + 2]).
Placement place_particles(const std::array<double, 3>& box_m, double d, std::int64_t count, double velocity_rms,
                          std::uint64_t seed);

/// Largest solids fraction `place_particles` accepts.
inline constexpr double kMaxPlacementFraction = 0.60;

}  // namespace cgd::dem
