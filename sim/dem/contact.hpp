#pragma once
// Linear spring-dashpot contact with tangential history spring and Coulomb slider
// (Cundall & Strack 1979, Geotechnique 29:47; parameters as in models.md "Soft-sphere contact"):
//   normal      F_n = max(0, k_n delta - gamma_n v_n)                       (no attraction)
//   tangential  xi  <- xi - n (n . xi) + v_t dt     (history spring kept in the tangent plane)
//               F_t = -k_t xi - gamma_t v_t,  |F_t| <= mu |F_n|;  when sliding, F_t is scaled to
//               mu|F_n| and xi is rescaled so that k_t |xi| = mu |F_n|.
//   torque on i  T_i = (-a_i n) x F_t,  lever arm a_i = R_i - delta/2: the contact point is the middle
//               of the overlap (n points from j to i), so a_i + a_j = |x_i - x_j| and the pair's forces
//               act at one point -- spin + orbital angular momentum is conserved exactly. (LAMMPS'
//               gran/hooke/history uses a_i = R_i, which leaks angular momentum in proportion to delta.)
// The evaluator is odd under exchange of i and j in exact IEEE arithmetic (every input flips sign,
// every operation commutes with negation), so F_ij = -F_ji bit for bit and the history of j is the
// negated history of i: momentum is conserved to round-off with a newton-off full neighbour list.
#include <cmath>
#include <cstddef>
#include <cstdint>
#if defined(__AVX2__)
#include <immintrin.h>
#endif

namespace cgd::dem {

struct ContactParams {
  double k_n = 0, k_t = 0;          // N/m
  double gamma_n = 0, gamma_t = 0;  // kg/s
  double friction = 0;              // Coulomb coefficient mu_pp
  double dt = 0;                    // s, for the history spring increment
};

struct V3 {
  double x, y, z;
};
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline V3 load3(const double* p) { return {p[0], p[1], p[2]}; }
inline void store3(double* p, V3 a) { p[0] = a.x; p[1] = a.y; p[2] = a.z; }

/// The touching entries of a run of neighbour-list rows, gathered for `SpringDashpot<true>::force_batch`:
/// a fixed-size structure of arrays (kSize entries, a multiple of 4; no memory that grows with the
/// particles). Inputs per entry b: dx = x_i - x_j, r2 = |dx|^2, dv = v_i - v_j, the spins w_i and w_j and
/// the spring xi; outputs: the force on i (`f`), the torque on i (`t`, what the entry adds to the row's sum),
/// the overlap and the new spring (in `xi`, over the old). `entry`, `row`, `i`, `j` are the caller's (where
/// the results go). Lanes past `count` hold stale or zero values: they are computed and never read.
template <std::size_t kSize>
struct FrictionBatch {
  static_assert(kSize % 4 == 0 && kSize > 0);
  static constexpr std::size_t size = kSize;
  alignas(32) double dx[3][kSize]{}, r2[kSize]{}, dv[3][kSize]{}, wi[3][kSize]{}, wj[3][kSize]{}, xi[3][kSize]{};
  alignas(32) double f[3][kSize]{}, t[3][kSize]{}, overlap[kSize]{};
  std::int64_t entry[kSize]{};
  std::int32_t row[kSize]{}, i[kSize]{}, j[kSize]{};
  std::size_t count = 0;
};

/// Force (and, with friction, torque) on particle i from its contact with j.
/// `dx` = x_i - x_j, `r` = |dx|, `overlap` = R_i + R_j - r > 0, `dv` = v_i - v_j.
/// Without friction the tangential part, the history and the torque are not computed at all.
template <bool kFriction>
struct SpringDashpot {
  ContactParams p;

  /// Frictionless: returns the force on i.
  inline V3 normal_force(V3 dx, double r, double overlap, V3 dv) const {
    const V3 n = (1.0 / r) * dx;
    const double vn = dot(dv, n);
    const double fn = std::max(0.0, p.k_n * overlap - p.gamma_n * vn);
    return fn * n;
  }

  /// Frictional: updates the history `xi` (3 doubles) and adds the torque on i to `torque_i`.
  inline V3 force(V3 dx, double r, double overlap, V3 dv, V3 w_i, V3 w_j, double radius_i, double radius_j,
                  double* xi, V3& torque_i) const {
    const V3 n = (1.0 / r) * dx;
    const double arm_i = radius_i - 0.5 * overlap, arm_j = radius_j - 0.5 * overlap;
    // relative velocity of the contact points: v_i - v_j - (a_i w_i + a_j w_j) x n
    const V3 vc = dv - cross(arm_i * w_i + arm_j * w_j, n);
    const double vn = dot(vc, n);
    const V3 vt = vc - vn * n;
    const double fn = std::max(0.0, p.k_n * overlap - p.gamma_n * vn);
    // history spring: keep it in the current tangent plane, then add this step's tangential slip
    V3 s = load3(xi);
    s = s - dot(n, s) * n;
    s = s + p.dt * vt;
    V3 ft = -p.k_t * s - p.gamma_t * vt;
    const double ft2 = dot(ft, ft);
    const double fmax = p.friction * fn;
    if (ft2 > fmax * fmax) {
      const double ft_mag = std::sqrt(ft2);
      ft = (fmax / ft_mag) * ft;
      const double s_mag = std::sqrt(dot(s, s));
      if (s_mag > 0.0) s = (fmax / (p.k_t * s_mag)) * s;
    }
    store3(xi, s);
    torque_i = torque_i + cross(-arm_i * n, ft);
    return fn * n + ft;
  }

  /// Frictional, over the first `b.count` entries of a batch (all of equal radius `radius`, touching at
  /// `contact_dist` = 2 radius): b.overlap, b.f, b.t (the torque's increment) and the new spring in b.xi.
  /// With AVX2 four entries at a time (issue 25: the scalar law's chains of dependent scalar multiplies and
  /// its division and square roots were the dense force pass's hottest instructions); else entry by entry
  /// through `force`.
  /// Bit for bit the scalar law: each lane does exactly `force`'s operations on the same operands in the
  /// same order (rr = sqrt(r2) and overlap as the force pass forms them, then 1/r, the products, sums and
  /// differences as `force` associates them; no FMA: -ffp-contract=off holds for intrinsics' operators
  /// too). IEEE division and square root are correctly rounded in every lane, as in scalar code. The two
  /// branches are selects with the same outcomes: std::max(0.0, x) is (0.0 < x) ? x : +0.0, and
  /// _mm256_max_pd(x, 0) is (x > 0) ? x : +0.0 (the second operand for a NaN, -0.0 or +0.0); the sliding test
  /// `ft2 > fmax*fmax` is an ordered compare (false for NaN) like the scalar `>`, and the spring's rescaling
  /// also needs `s_mag > 0.0`. The rescaled values of lanes that do not slide are computed (they may be
  /// inf or NaN) and discarded; floating-point traps are not enabled anywhere in cgd.
  template <std::size_t kSize>
  inline void force_batch(FrictionBatch<kSize>& b, double contact_dist, double radius) const {
    std::size_t e = 0;
#if defined(__AVX2__)
    using D4 = __m256d;  // GCC/Clang vector type: + - * / are the lanes' IEEE operations
    const D4 cd = _mm256_set1_pd(contact_dist), rad = _mm256_set1_pd(radius), half = _mm256_set1_pd(0.5);
    const D4 one = _mm256_set1_pd(1.0), zero = _mm256_setzero_pd(), sign = _mm256_set1_pd(-0.0);
    const D4 kn = _mm256_set1_pd(p.k_n), gn = _mm256_set1_pd(p.gamma_n), kt = _mm256_set1_pd(p.k_t);
    const D4 minus_kt = _mm256_set1_pd(-p.k_t), gt = _mm256_set1_pd(p.gamma_t), mu = _mm256_set1_pd(p.friction);
    const D4 dt = _mm256_set1_pd(p.dt);
    for (; e < b.count; e += 4) {
      const D4 rr = _mm256_sqrt_pd(_mm256_load_pd(b.r2 + e));
      const D4 overlap = cd - rr;
      _mm256_store_pd(b.overlap + e, overlap);
      const D4 inv_r = one / rr;
      const D4 nx = inv_r * _mm256_load_pd(b.dx[0] + e), ny = inv_r * _mm256_load_pd(b.dx[1] + e),
               nz = inv_r * _mm256_load_pd(b.dx[2] + e);
      const D4 arm_i = rad - half * overlap, arm_j = rad - half * overlap;
      const D4 ax = arm_i * _mm256_load_pd(b.wi[0] + e) + arm_j * _mm256_load_pd(b.wj[0] + e);
      const D4 ay = arm_i * _mm256_load_pd(b.wi[1] + e) + arm_j * _mm256_load_pd(b.wj[1] + e);
      const D4 az = arm_i * _mm256_load_pd(b.wi[2] + e) + arm_j * _mm256_load_pd(b.wj[2] + e);
      const D4 vcx = _mm256_load_pd(b.dv[0] + e) - (ay * nz - az * ny);
      const D4 vcy = _mm256_load_pd(b.dv[1] + e) - (az * nx - ax * nz);
      const D4 vcz = _mm256_load_pd(b.dv[2] + e) - (ax * ny - ay * nx);
      const D4 vn = vcx * nx + vcy * ny + vcz * nz;
      const D4 vtx = vcx - vn * nx, vty = vcy - vn * ny, vtz = vcz - vn * nz;
      const D4 fn = _mm256_max_pd(kn * overlap - gn * vn, zero);
      D4 sx = _mm256_load_pd(b.xi[0] + e), sy = _mm256_load_pd(b.xi[1] + e), sz = _mm256_load_pd(b.xi[2] + e);
      const D4 ns = nx * sx + ny * sy + nz * sz;
      sx = sx - ns * nx;
      sy = sy - ns * ny;
      sz = sz - ns * nz;
      sx = sx + dt * vtx;
      sy = sy + dt * vty;
      sz = sz + dt * vtz;
      D4 ftx = minus_kt * sx - gt * vtx, fty = minus_kt * sy - gt * vty, ftz = minus_kt * sz - gt * vtz;
      const D4 ft2 = ftx * ftx + fty * fty + ftz * ftz;
      const D4 fmax = mu * fn;
      const D4 slide = _mm256_cmp_pd(ft2, fmax * fmax, _CMP_GT_OQ);
      if (_mm256_movemask_pd(slide) != 0) {  // else every lane keeps ft and s: the two square roots and
                                             // divisions of the slider are skipped
        const D4 ft_scale = fmax / _mm256_sqrt_pd(ft2);
        ftx = _mm256_blendv_pd(ftx, ft_scale * ftx, slide);
        fty = _mm256_blendv_pd(fty, ft_scale * fty, slide);
        ftz = _mm256_blendv_pd(ftz, ft_scale * ftz, slide);
        const D4 s_mag = _mm256_sqrt_pd(sx * sx + sy * sy + sz * sz);
        const D4 rescale = _mm256_and_pd(slide, _mm256_cmp_pd(s_mag, zero, _CMP_GT_OQ));
        const D4 s_scale = fmax / (kt * s_mag);
        sx = _mm256_blendv_pd(sx, s_scale * sx, rescale);
        sy = _mm256_blendv_pd(sy, s_scale * sy, rescale);
        sz = _mm256_blendv_pd(sz, s_scale * sz, rescale);
      }
      _mm256_store_pd(b.xi[0] + e, sx);
      _mm256_store_pd(b.xi[1] + e, sy);
      _mm256_store_pd(b.xi[2] + e, sz);
      const D4 minus_arm = _mm256_xor_pd(arm_i, sign);  // -arm_i, exact
      const D4 lx = minus_arm * nx, ly = minus_arm * ny, lz = minus_arm * nz;
      _mm256_store_pd(b.t[0] + e, ly * ftz - lz * fty);
      _mm256_store_pd(b.t[1] + e, lz * ftx - lx * ftz);
      _mm256_store_pd(b.t[2] + e, lx * fty - ly * ftx);
      _mm256_store_pd(b.f[0] + e, fn * nx + ftx);
      _mm256_store_pd(b.f[1] + e, fn * ny + fty);
      _mm256_store_pd(b.f[2] + e, fn * nz + ftz);
    }
#endif
    for (; e < b.count; ++e) {  // without AVX2: the scalar law itself
      const double rr = std::sqrt(b.r2[e]);
      const double overlap = contact_dist - rr;
      b.overlap[e] = overlap;
      double s[3] = {b.xi[0][e], b.xi[1][e], b.xi[2][e]};
      V3 t{0, 0, 0};
      const V3 f = force({b.dx[0][e], b.dx[1][e], b.dx[2][e]}, rr, overlap, {b.dv[0][e], b.dv[1][e], b.dv[2][e]},
                         {b.wi[0][e], b.wi[1][e], b.wi[2][e]}, {b.wj[0][e], b.wj[1][e], b.wj[2][e]}, radius, radius,
                         s, t);
      for (int c = 0; c < 3; ++c) b.xi[c][e] = s[c];
      b.f[0][e] = f.x, b.f[1][e] = f.y, b.f[2][e] = f.z;
      b.t[0][e] = t.x, b.t[1][e] = t.y, b.t[2][e] = t.z;
    }
  }
};

}  // namespace cgd::dem
