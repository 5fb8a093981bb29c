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
};

}  // namespace cgd::dem
