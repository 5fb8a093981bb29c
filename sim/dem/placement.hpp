#pragma once
// Initial particle placement without overlap in a periodic box.
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

/// Place `count` spheres of diameter `d` at random without overlap, deterministic in `seed` (every
/// rank computes the same placement, so runs at any rank count start from the same state).
/// Random sequential addition (RSA) up to a solids fraction of 0.30 (RSA jams near 0.38 and slows
/// down well before); denser packings start from RSA of smaller spheres which are then grown to
/// the target diameter by a frictionless, strongly damped soft-sphere relaxation (Lubachevsky-
/// Stillinger-like growth), ending without overlap. Velocities: Gaussian with rms speed
/// `velocity_rms` (per component rms/sqrt(3)), zero total momentum.
Placement place_particles(const std::array<double, 3>& box_m, double d, std::int64_t count, double velocity_rms,
                          std::uint64_t seed);

/// Largest solids fraction `place_particles` accepts.
inline constexpr double kMaxPlacementFraction = 0.60;

}  // namespace cgd::dem
