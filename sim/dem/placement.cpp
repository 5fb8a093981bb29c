#include "sim/dem/placement.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "core/error.hpp"

namespace cgd::dem {

namespace {

/// Random sequential addition of `count` spheres of diameter `d` (cell list of edge d).
bool rsa(const std::array<double, 3>& L, double d, std::int64_t count, std::mt19937_64& rng,
         std::vector<double>& x) {
  std::array<int, 3> n{};
  for (int k = 0; k < 3; ++k) n[k] = std::max(1, static_cast<int>(L[k] / d));
  const std::size_t ncell = static_cast<std::size_t>(n[0]) * n[1] * n[2];
  std::vector<std::int64_t> head(ncell, -1), next(static_cast<std::size_t>(count), -1);
  x.assign(3 * static_cast<std::size_t>(count), 0.0);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const double dmin2 = d * d;
  std::int64_t placed = 0, tries = 0;
  const std::int64_t max_tries = 5000 * std::max<std::int64_t>(count, 1);
  while (placed < count) {
    if (++tries > max_tries) return false;
    double p[3];
    int c[3];
    for (int k = 0; k < 3; ++k) {
      p[k] = U(rng) * L[k];
      c[k] = std::min(n[k] - 1, static_cast<int>(p[k] / L[k] * n[k]));
    }
    bool ok = true;
    for (int a = -1; a <= 1 && ok; ++a)
      for (int b = -1; b <= 1 && ok; ++b)
        for (int e = -1; e <= 1 && ok; ++e) {
          const int cc[3] = {(c[0] + a + n[0]) % n[0], (c[1] + b + n[1]) % n[1], (c[2] + e + n[2]) % n[2]};
          for (std::int64_t j = head[(static_cast<std::size_t>(cc[2]) * n[1] + cc[1]) * n[0] + cc[0]]; j >= 0;
               j = next[j]) {
            double r2 = 0;
            for (int k = 0; k < 3; ++k) {
              double dx = p[k] - x[3 * j + k];
              dx -= L[k] * std::round(dx / L[k]);
              r2 += dx * dx;
            }
            if (r2 < dmin2) {
              ok = false;
              break;
            }
          }
        }
    if (!ok) continue;
    const std::size_t id = (static_cast<std::size_t>(c[2]) * n[1] + c[1]) * n[0] + c[0];
    for (int k = 0; k < 3; ++k) x[3 * placed + k] = p[k];
    next[placed] = head[id];
    head[id] = placed;
    ++placed;
  }
  return true;
}

/// Smallest centre distance (periodic) relative to d, by brute force over a cell list of edge d.
double min_distance_rel(const std::array<double, 3>& L, double d, const std::vector<double>& x) {
  const std::size_t N = x.size() / 3;
  std::array<int, 3> n{};
  for (int k = 0; k < 3; ++k) n[k] = std::max(1, static_cast<int>(L[k] / d));
  const std::size_t ncell = static_cast<std::size_t>(n[0]) * n[1] * n[2];
  std::vector<std::int64_t> head(ncell, -1), next(N, -1);
  auto cell_of = [&](const double* p, int* c) {
    for (int k = 0; k < 3; ++k) {
      double q = p[k] - L[k] * std::floor(p[k] / L[k]);
      c[k] = std::min(n[k] - 1, static_cast<int>(q / L[k] * n[k]));
    }
  };
  for (std::size_t i = 0; i < N; ++i) {
    int c[3];
    cell_of(&x[3 * i], c);
    const std::size_t id = (static_cast<std::size_t>(c[2]) * n[1] + c[1]) * n[0] + c[0];
    next[i] = head[id];
    head[id] = static_cast<std::int64_t>(i);
  }
  double best2 = HUGE_VAL;
  for (std::size_t i = 0; i < N; ++i) {
    int c[3];
    cell_of(&x[3 * i], c);
    for (int a = -1; a <= 1; ++a)
      for (int b = -1; b <= 1; ++b)
        for (int e = -1; e <= 1; ++e) {
          const int cc[3] = {(c[0] + a + n[0]) % n[0], (c[1] + b + n[1]) % n[1], (c[2] + e + n[2]) % n[2]};
          for (std::int64_t j = head[(static_cast<std::size_t>(cc[2]) * n[1] + cc[1]) * n[0] + cc[0]]; j >= 0;
               j = next[j]) {
            if (static_cast<std::size_t>(j) == i) continue;
            double r2 = 0;
            for (int k = 0; k < 3; ++k) {
              double dx = x[3 * i + k] - x[3 * j + k];
              dx -= L[k] * std::round(dx / L[k]);
              r2 += dx * dx;
            }
            best2 = std::min(best2, r2);
          }
        }
  }
  return std::sqrt(best2) / d;
}

}  // namespace

// Growth of an RSA packing of small spheres to diameter d: defined in growth.cpp.
bool grow_packing(const std::array<double, 3>& L, double d_start, double d_target, std::vector<double>& x);

Placement place_particles(const std::array<double, 3>& L, double d, std::int64_t count, double velocity_rms,
                          std::uint64_t seed) {
  Placement out;
  const double volume = L[0] * L[1] * L[2];
  const double phi = static_cast<double>(count) * std::numbers::pi / 6.0 * d * d * d / volume;
  if (phi > kMaxPlacementFraction)
    throw InputError("cannot place " + std::to_string(count) + " particles: solids fraction " + std::to_string(phi) +
                     " exceeds what the placement reaches (" + std::to_string(kMaxPlacementFraction) + ")");
  std::mt19937_64 rng(seed);
  constexpr double kRsaLimit = 0.30;
  // a gap of 1e-3 d keeps the first contacts from starting overlapped by round-off
  const double d_safe = d * (1.0 + 1e-3);
  if (phi <= kRsaLimit) {
    if (!rsa(L, d_safe, count, rng, out.position))
      throw InputError("random sequential addition stalled placing " + std::to_string(count) + " particles");
    out.method = "random sequential addition";
  } else {
    // RSA at solids fraction 0.25 with smaller spheres, then growth to d (see header).
    const double d_start = d_safe * std::cbrt(0.25 / phi);
    if (!rsa(L, d_start, count, rng, out.position))
      throw InputError("random sequential addition stalled placing " + std::to_string(count) + " seeds");
    if (!grow_packing(L, d_start, d_safe, out.position))
      throw InputError("growing the packing to solids fraction " + std::to_string(phi) +
                       " did not converge; lower particles.solids_fraction");
    out.method = "random sequential addition at solids fraction 0.25, then frictionless growth";
  }
  out.min_gap_rel = count > 1 ? min_distance_rel(L, d, out.position) - 1.0 : 0.0;
  // velocities: Gaussian, zero total momentum
  out.velocity.assign(3 * static_cast<std::size_t>(count), 0.0);
  if (velocity_rms > 0 && count > 0) {
    std::normal_distribution<double> G(0.0, velocity_rms / std::sqrt(3.0));
    double mean[3] = {0, 0, 0};
    for (std::size_t i = 0; i < out.velocity.size(); ++i) {
      out.velocity[i] = G(rng);
      mean[i % 3] += out.velocity[i];
    }
    if (count > 1)
      for (std::size_t i = 0; i < out.velocity.size(); ++i) out.velocity[i] -= mean[i % 3] / static_cast<double>(count);
  }
  return out;
}

}  // namespace cgd::dem
