#include "sim/dem/placement.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>
#include <unordered_map>

#include "core/error.hpp"
#include "core/scales.hpp"
#include "sim/dem/system.hpp"

namespace cgd::dem {

namespace {

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// The initial velocity of particle `id`: Gaussian, rms speed velocity_rms, from a stream of its own.
void particle_velocity(std::uint64_t seed, std::int64_t id, double velocity_rms, double* v) {
  std::mt19937_64 rng(splitmix64(seed ^ splitmix64(static_cast<std::uint64_t>(id) + 0x5DEECE66Dull)));
  std::normal_distribution<double> G(0.0, velocity_rms / std::sqrt(3.0));
  for (int c = 0; c < 3; ++c) v[c] = G(rng);
}

/// Fixed y-blocks of the box for the block-wise RSA (placement.hpp): their number depends on the box
/// and the diameter only, never on the rank count.
struct Blocks {
  int count = 1;        // B
  int colours = 1;
  double height = 0;    // m
  std::int64_t particles = 0;
  Blocks(double box_y, double d, std::int64_t n) : particles(n) {
    count = static_cast<int>(std::clamp(std::floor(box_y / (8.0 * d)), 1.0, 256.0));
    height = box_y / count;
    colours = count == 1 ? 1 : (count % 2 == 0 ? 2 : 3);
  }
  std::int64_t first(int b) const {
    return static_cast<std::int64_t>(static_cast<__int128>(particles) * b / count);
  }
  int colour(int b) const { return colours == 3 && b == count - 1 ? 2 : b % 2; }
  /// Owner of block b among the first `k` ranks: contiguous ranges.
  int owner(int b, int k) const {
    for (int r = 0; r < k; ++r)
      if (b < static_cast<int>(static_cast<std::int64_t>(count) * (r + 1) / k)) return r;
    return k - 1;
  }
};

/// Random sequential addition of `n` spheres of diameter d into y in [y0, y1) (x, z over the box,
/// periodic), avoiding `fixed` (positions already placed in and beside the block, y unwrapped to lie
/// within d of [y0, y1)). With `periodic_y` the block is the whole box and y is periodic too.
bool rsa_block(const std::array<double, 3>& L, double d, double y0, double y1, bool periodic_y, std::int64_t n,
               const std::vector<double>& fixed, std::mt19937_64& rng, std::vector<double>& out) {
  const double lo = periodic_y ? 0.0 : y0 - d;
  const double span = periodic_y ? L[1] : (y1 - y0) + 2.0 * d;
  const int nx = std::max(1, static_cast<int>(L[0] / d)), nz = std::max(1, static_cast<int>(L[2] / d));
  const int ny = std::max(1, static_cast<int>(span / d));
  std::vector<std::int64_t> head(static_cast<std::size_t>(nx) * ny * nz, -1);
  std::vector<double> pts(fixed);
  pts.reserve(fixed.size() + 3 * static_cast<std::size_t>(n));
  std::vector<std::int64_t> next;
  next.reserve(pts.capacity() / 3);
  auto cell = [&](const double* p, int* c) {
    c[0] = std::min(nx - 1, static_cast<int>(p[0] / L[0] * nx));
    c[1] = std::clamp(static_cast<int>((p[1] - lo) / span * ny), 0, ny - 1);
    c[2] = std::min(nz - 1, static_cast<int>(p[2] / L[2] * nz));
  };
  auto insert = [&](std::size_t i) {
    int c[3];
    cell(&pts[3 * i], c);
    const std::size_t id = (static_cast<std::size_t>(c[2]) * ny + c[1]) * nx + c[0];
    next.push_back(head[id]);
    head[id] = static_cast<std::int64_t>(i);
  };
  for (std::size_t i = 0; i < fixed.size() / 3; ++i) insert(i);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const double dmin2 = d * d;
  const std::int64_t max_tries = 5000 * std::max<std::int64_t>(n, 1);
  std::int64_t placed = 0, tries = 0;
  while (placed < n) {
    if (++tries > max_tries) return false;
    double p[3] = {U(rng) * L[0], y0 + U(rng) * (y1 - y0), U(rng) * L[2]};
    int c[3];
    cell(p, c);
    bool ok = true;
    for (int a = -1; a <= 1 && ok; ++a)
      for (int b = -1; b <= 1 && ok; ++b) {
        int cy = c[1] + b;
        if (periodic_y) cy = (cy + ny) % ny;
        else if (cy < 0 || cy >= ny) continue;
        for (int e = -1; e <= 1 && ok; ++e) {
          const int cx = (c[0] + a + nx) % nx, cz = (c[2] + e + nz) % nz;
          for (std::int64_t j = head[(static_cast<std::size_t>(cz) * ny + cy) * nx + cx]; j >= 0; j = next[j]) {
            double r2 = 0;
            for (int k = 0; k < 3; ++k) {
              double dx = p[k] - pts[3 * j + k];
              if (k != 1 || periodic_y) dx -= L[k] * std::round(dx / L[k]);
              r2 += dx * dx;
            }
            if (r2 < dmin2) {
              ok = false;
              break;
            }
          }
        }
      }
    if (!ok) continue;
    pts.insert(pts.end(), p, p + 3);
    insert(pts.size() / 3 - 1);
    out.insert(out.end(), p, p + 3);
    ++placed;
  }
  return true;
}

/// Smallest centre distance / d over the pairs of a DemSystem's owned particles with its owned and
/// ghost particles (ghosts are periodic images, so plain distances), reduced over the ranks; pairs
/// farther than the cutoff are not seen (then the cutoff is returned).
double min_distance_rel(const DemSystem& sys, double d) {
  const Particles& p = sys.particles();
  const double h = sys.cutoff();
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> cells;
  auto key = [&](const double* x, int a, int b, int e) {
    const std::int64_t i = static_cast<std::int64_t>(std::floor(x[0] / h)) + a;
    const std::int64_t j = static_cast<std::int64_t>(std::floor(x[1] / h)) + b;
    const std::int64_t k = static_cast<std::int64_t>(std::floor(x[2] / h)) + e;
    return (i * 1000003 + j) * 1000003 + k;
  };
  for (std::size_t i = 0; i < p.n_total; ++i) cells[key(&p.x[3 * i], 0, 0, 0)].push_back(static_cast<std::uint32_t>(i));
  double best2 = h * h;
  for (std::size_t i = 0; i < p.n_owned; ++i)
    for (int a = -1; a <= 1; ++a)
      for (int b = -1; b <= 1; ++b)
        for (int e = -1; e <= 1; ++e) {
          const auto it = cells.find(key(&p.x[3 * i], a, b, e));
          if (it == cells.end()) continue;
          for (const std::uint32_t j : it->second) {
            if (p.id[j] == p.id[i]) continue;
            double r2 = 0;
            for (int k = 0; k < 3; ++k) {
              const double dx = p.x[3 * i + k] - p.x[3 * j + k];
              r2 += dx * dx;
            }
            best2 = std::min(best2, r2);
          }
        }
  MPI_Allreduce(MPI_IN_PLACE, &best2, 1, MPI_DOUBLE, MPI_MIN, sys.slabs().comm());
  return std::sqrt(best2) / d;
}

DemSettings relaxation_settings(const std::array<double, 3>& box, double d) {
  // frictionless, strongly damped soft spheres of unit mass and stiffness (lengths in the target d)
  const cgd::SpringDashpot sd = spring_dashpot(1.0, 0.1, 0.5, 3.5, 1.0);
  DemSettings s;
  s.box_m = box;
  s.diameter_m = d;
  s.mass_kg = 1.0;
  // t_c/12: half the steps of t_c/25 to the same relaxed state (measured at phi 0.40: 107 instead of 217
  // in the last stage, the same contact peak and fabric); the explicit limit with ~6 contacts is ~t_c/4
  s.dt_s = sd.t_c / 12.0;
  s.contacts = true;
  s.friction = false;
  s.contact.k_n = sd.k_n;
  s.contact.gamma_n = sd.gamma_n;
  s.contact.dt = s.dt_s;
  s.skin_m = 0.1 * d;
  s.drive.drag_rate = 2.0 / sd.t_c;  // overdamped motion: relaxes overlaps in a few contact times
  s.overlap_limit = 0.5;
  return s;
}

}  // namespace

LocalPlacement place_particles_distributed(MPI_Comm comm, const std::array<double, 3>& L, double d,
                                           std::int64_t count, double velocity_rms, std::uint64_t seed) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const double volume = L[0] * L[1] * L[2];
  const double phi = static_cast<double>(count) * std::numbers::pi / 6.0 * d * d * d / volume;
  if (phi > kMaxPlacementFraction)
    throw InputError("cannot place " + std::to_string(count) + " particles: solids fraction " + std::to_string(phi) +
                     " exceeds what the placement reaches (" + std::to_string(kMaxPlacementFraction) + ")");
  constexpr double kRsaLimit = 0.30;
  // a gap of 1e-3 d keeps the first contacts from starting overlapped by round-off
  const double d_safe = d * (1.0 + 1e-3);
  const bool grow = phi > kRsaLimit;
  const double d_rsa = grow ? d_safe * std::cbrt(0.25 / phi) : d_safe;

  // Active ranks: at most one per block, and slabs of the relaxation at least 1.2 d high.
  const Blocks blocks(L[1], d_safe, count);
  const int k = std::max(1, std::min({size, blocks.count, static_cast<int>(L[1] / (1.2 * d_safe))}));
  MPI_Comm work = MPI_COMM_NULL;
  MPI_Comm_split(comm, rank < k ? 0 : MPI_UNDEFINED, rank, &work);

  LocalPlacement out;
  std::vector<std::int64_t> ids;
  std::vector<double> x;
  std::vector<double> block_momentum(3 * static_cast<std::size_t>(blocks.count), 0.0);
  int failed = 0;
  if (rank < k) {
    // ---- block-wise RSA in colour phases
    std::vector<int> mine;
    for (int b = 0; b < blocks.count; ++b)
      if (blocks.owner(b, k) == rank) mine.push_back(b);
    std::unordered_map<int, std::vector<double>> halo;  // fixed neighbours of each of my blocks
    std::unordered_map<int, std::vector<double>> placed;
    for (int colour = 0; colour < blocks.colours; ++colour) {
      std::vector<std::vector<double>> send(static_cast<std::size_t>(k));
      for (const int b : mine) {
        if (blocks.colour(b) != colour) continue;
        const double y0 = b * blocks.height, y1 = (b + 1) * blocks.height;
        std::mt19937_64 rng(splitmix64(seed ^ splitmix64(static_cast<std::uint64_t>(b) + 1)));
        std::vector<double>& pts = placed[b];
        const std::int64_t n = blocks.first(b + 1) - blocks.first(b);
        if (!rsa_block(L, d_rsa, y0, y1, blocks.count == 1, n, halo[b], rng, pts)) failed = 1;
        halo.erase(b);
        if (blocks.count == 1) continue;
        // the bands within d_rsa of the faces go to the neighbouring blocks, y unwrapped for them
        const int below = (b + blocks.count - 1) % blocks.count, above = (b + 1) % blocks.count;
        for (std::size_t i = 0; i < pts.size() / 3; ++i) {
          const double* p = &pts[3 * i];
          if (p[1] < y0 + d_rsa && blocks.colour(below) > colour) {
            auto& to = send[static_cast<std::size_t>(blocks.owner(below, k))];
            to.insert(to.end(), {static_cast<double>(below), p[0], b == 0 ? p[1] + L[1] : p[1], p[2]});
          }
          if (p[1] >= y1 - d_rsa && blocks.colour(above) > colour) {
            auto& to = send[static_cast<std::size_t>(blocks.owner(above, k))];
            to.insert(to.end(), {static_cast<double>(above), p[0], b == blocks.count - 1 ? p[1] - L[1] : p[1], p[2]});
          }
        }
      }
      // exchange the bands (all-to-all among the active ranks; each entry: block, x, y, z)
      std::vector<int> scount(static_cast<std::size_t>(k)), rcount(static_cast<std::size_t>(k)), sdisp(k), rdisp(k);
      std::vector<double> sbuf;
      for (int r = 0; r < k; ++r) {
        scount[r] = static_cast<int>(send[r].size());
        sdisp[r] = static_cast<int>(sbuf.size());
        sbuf.insert(sbuf.end(), send[r].begin(), send[r].end());
      }
      MPI_Alltoall(scount.data(), 1, MPI_INT, rcount.data(), 1, MPI_INT, work);
      int total = 0;
      for (int r = 0; r < k; ++r) {
        rdisp[r] = total;
        total += rcount[r];
      }
      std::vector<double> rbuf(static_cast<std::size_t>(total));
      MPI_Alltoallv(sbuf.data(), scount.data(), sdisp.data(), MPI_DOUBLE, rbuf.data(), rcount.data(), rdisp.data(),
                    MPI_DOUBLE, work);
      for (std::size_t q = 0; q + 4 <= rbuf.size(); q += 4) {
        auto& h = halo[static_cast<int>(rbuf[q])];
        h.insert(h.end(), &rbuf[q + 1], &rbuf[q + 4]);
      }
      MPI_Allreduce(MPI_IN_PLACE, &failed, 1, MPI_INT, MPI_MAX, work);
      if (failed) break;
    }
    if (!failed)
      for (const int b : mine) {
        const std::vector<double>& pts = placed[b];
        const std::int64_t first = blocks.first(b);
        double* sum = &block_momentum[3 * static_cast<std::size_t>(b)];
        for (std::size_t i = 0; i < pts.size() / 3; ++i) {
          const std::int64_t id = first + static_cast<std::int64_t>(i);
          ids.push_back(id);
          x.insert(x.end(), &pts[3 * i], &pts[3 * i + 3]);
          if (velocity_rms > 0) {  // the block's velocity sum in id order (deterministic mean below)
            double v[3];
            particle_velocity(seed, id, velocity_rms, v);
            for (int c = 0; c < 3; ++c) sum[c] += v[c];
          }
        }
      }
  }
  MPI_Allreduce(MPI_IN_PLACE, &failed, 1, MPI_INT, MPI_MAX, comm);
  if (failed) {
    if (work != MPI_COMM_NULL) MPI_Comm_free(&work);
    throw InputError("random sequential addition stalled placing " + std::to_string(count) +
                     (grow ? " seeds" : " particles"));
  }
  // every block's sum is on one rank only: the sum over ranks is exact, the sum over blocks in block order
  MPI_Allreduce(MPI_IN_PLACE, block_momentum.data(), static_cast<int>(block_momentum.size()), MPI_DOUBLE, MPI_SUM,
                comm);
  double mean[3] = {0, 0, 0};
  for (int b = 0; b < blocks.count; ++b)
    for (int c = 0; c < 3; ++c) mean[c] += block_momentum[3 * static_cast<std::size_t>(b) + c];
  for (double& m : mean) m /= static_cast<double>(std::max<std::int64_t>(count, 1));

  // ---- growth and the final check, slab-parallel on the active ranks (lengths in units of d)
  int converged = 1;
  if (rank < k) {
    const std::array<double, 3> box{L[0] / d, L[1] / d, L[2] / d};
    for (double& q : x) q /= d;
    std::vector<double> stages;  // diameters, in d
    if (grow) {
      const int n = std::max(1, static_cast<int>(std::ceil(std::log(d_safe / d_rsa) / std::log(1.06))));
      for (int s = 1; s <= n; ++s) stages.push_back(s == n ? d_safe / d : d_rsa / d * std::pow(d_safe / d_rsa, double(s) / n));
    } else {
      stages.push_back(d_safe / d);
    }
    for (std::size_t s = 0; s < stages.size(); ++s) {
      const bool last = s + 1 == stages.size();
      DemSystem sys(relaxation_settings(box, stages[s]), work);
      sys.set_particles(ids, x, std::vector<double>(x.size(), 0.0), {});
      if (grow) {
        // intermediate stages only take the overlaps down to 5 %; the last to 2e-4 of the diameter
        const double tolerance = last ? 2e-4 : 5e-2;
        const int max_steps = last ? 20000 : 2000;
        double overlap = 1.0;
        for (int it = 0; it < max_steps && overlap > tolerance; ++it) {
          sys.step();
          overlap = sys.last_max_overlap_rel();
        }
        if (last && overlap > tolerance) converged = 0;
      }
      sys.prepare();  // wrapped, migrated to the owners, ghosts current
      const Particles& p = sys.particles();
      ids.assign(p.id.begin(), p.id.begin() + static_cast<std::ptrdiff_t>(p.n_owned));
      x.assign(p.x.begin(), p.x.begin() + 3 * static_cast<std::ptrdiff_t>(p.n_owned));
      if (last) out.min_gap_rel = count > 1 ? min_distance_rel(sys, 1.0) - 1.0 : 0.0;
    }
    for (std::size_t i = 0; i < x.size(); ++i) {
      double q = x[i] * d;
      const double edge = L[i % 3];
      q -= edge * std::floor(q / edge);
      x[i] = q < edge ? q : 0.0;
    }
    MPI_Comm_free(&work);
  }
  MPI_Allreduce(MPI_IN_PLACE, &converged, 1, MPI_INT, MPI_MIN, comm);
  if (!converged)
    throw InputError("growing the packing to solids fraction " + std::to_string(phi) +
                     " did not converge; lower particles.solids_fraction");
  MPI_Bcast(&out.min_gap_rel, 1, MPI_DOUBLE, 0, comm);
  out.method = grow ? "random sequential addition at solids fraction 0.25, then frictionless growth"
                    : "random sequential addition";
  out.id = std::move(ids);
  out.position = std::move(x);
  out.velocity.assign(out.position.size(), 0.0);
  if (velocity_rms > 0)
    for (std::size_t i = 0; i < out.id.size(); ++i) {
      particle_velocity(seed, out.id[i], velocity_rms, &out.velocity[3 * i]);
      if (count > 1)
        for (int c = 0; c < 3; ++c) out.velocity[3 * i + c] -= mean[c];
    }
  return out;
}

Placement place_particles(const std::array<double, 3>& L, double d, std::int64_t count, double velocity_rms,
                          std::uint64_t seed) {
  LocalPlacement local = place_particles_distributed(MPI_COMM_SELF, L, d, count, velocity_rms, seed);
  Placement out;
  out.position.assign(3 * static_cast<std::size_t>(count), 0.0);
  out.velocity.assign(3 * static_cast<std::size_t>(count), 0.0);
  for (std::size_t i = 0; i < local.id.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      out.position[3 * local.id[i] + c] = local.position[3 * i + c];
      out.velocity[3 * local.id[i] + c] = local.velocity[3 * i + c];
    }
  out.method = local.method;
  out.min_gap_rel = local.min_gap_rel;
  return out;
}

}  // namespace cgd::dem
