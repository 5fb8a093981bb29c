#pragma once
// The fused DEM step: contact forces and leapfrog (kick-drift, symplectic, second order) in one
// streaming pass over the owned particles,
//   v_{n+1/2} = v_{n-1/2} + dt a_n,   x_{n+1} = x_n + dt v_{n+1/2},   w_{n+1/2} = w_{n-1/2} + dt T_n / I,
// with a_n = (sum_j F_ij)/m + a_ext(v_{n-1/2}). The state is double-buffered (particles.hpp), so the
// pass reads neighbours at step n while it writes step n+1, and no force array is stored. Velocity-
// dependent forces (dashpots, drag) use v_{n-1/2}, the same half-step lag as LAMMPS' velocity Verlet.
// The contact model and the external forces are template parameters: an effect that is off
// generates no code in the loop.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "sim/dem/contact.hpp"
#include "sim/dem/neighbor.hpp"
#include "sim/dem/particles.hpp"

namespace cgd::dem {

/// No contacts: no neighbour list exists at all.
struct NoContact {};

/// External acceleration a = g_eff - lambda v: gravity (with buoyancy folded into g_eff when the
/// quiescent fluid's pressure-gradient force is on) and linear drag toward a fluid at rest
/// (Stokes: lambda = 3 pi mu d / m). lambda = 0 for a dry run.
struct UniformDrive {
  V3 accel{0, 0, 0};
  double drag_rate = 0;  // 1/s
  inline V3 operator()(std::size_t, V3 v) const { return accel - drag_rate * v; }
};

/// Per-particle external acceleration, constant over the DEM sub-steps of a fluid step (coupled runs:
/// drag from the fluid, pressure-gradient force, gravity and the periodic driving; sim/coupling).
struct PerParticleDrive {
  const double* accel = nullptr;  // 3 per owned particle
  inline V3 operator()(std::size_t i, V3) const { return load3(accel + 3 * i); }
};

struct KernelStats {
  double max_speed2 = 0;      // max |v_{n+1/2}|^2 (NaN if any velocity is NaN)
  double max_overlap = 0;     // m
  std::int64_t overlap_particle = -1, overlap_partner = -1;
  std::int64_t bad_particle = -1;  // first particle with a non-finite velocity
};

struct KernelConstants {
  double dt = 0, radius = 0, inv_mass = 0, inv_inertia = 0;
};

template <class Contact, class Drive>
KernelStats advance_particles(Particles& p, NeighborList& list, const Contact& contact, const Drive& drive,
                              const KernelConstants& k) {
  KernelStats st;
  const double dt = k.dt, contact_dist = 2.0 * k.radius, contact_dist2 = contact_dist * contact_dist;
  const double* __restrict x = p.x.data();
  const double* __restrict v = p.v.data();
  double* __restrict xn = p.x_next.data();
  double* __restrict vn = p.v_next.data();
  for (std::size_t i = 0; i < p.n_owned; ++i) {
    const V3 xi = load3(x + 3 * i), vi = load3(v + 3 * i);
    V3 f{0, 0, 0};
    V3 torque{0, 0, 0};
    V3 wi{0, 0, 0};
    constexpr bool kContacts = !std::is_same_v<Contact, NoContact>;
    constexpr bool kFriction = std::is_same_v<Contact, SpringDashpot<true>>;
    if constexpr (kFriction) wi = load3(p.w.data() + 3 * i);
    if constexpr (kContacts) {
      const std::int64_t k0 = list.offset[i], k1 = list.offset[i + 1];
      for (std::int64_t e = k0; e < k1; ++e) {
        const std::int32_t j = list.index[e];
        const V3 dx = xi - load3(x + 3 * j);
        const double r2 = dot(dx, dx);
        if (r2 >= contact_dist2) {
          if constexpr (kFriction) {
            double* s = &list.xi[3 * e];
            s[0] = s[1] = s[2] = 0.0;  // contact ended: its history goes with it
          }
          continue;
        }
        const double r = std::sqrt(r2);
        const double overlap = contact_dist - r;
        if (overlap > st.max_overlap) {
          st.max_overlap = overlap;
          st.overlap_particle = p.id[i];
          st.overlap_partner = p.id[j];
        }
        const V3 dv = vi - load3(v + 3 * j);
        if constexpr (kFriction) {
          f = f + contact.force(dx, r, overlap, dv, wi, load3(p.w.data() + 3 * j), k.radius, k.radius,
                                &list.xi[3 * e], torque);
        } else {
          f = f + contact.normal_force(dx, r, overlap, dv);
        }
      }
    }
    const V3 a = k.inv_mass * f + drive(i, vi);
    const V3 v_new = vi + dt * a;
    const V3 x_new = xi + dt * v_new;
    store3(vn + 3 * i, v_new);
    store3(xn + 3 * i, x_new);
    if constexpr (kFriction) store3(p.w_next.data() + 3 * i, wi + (dt * k.inv_inertia) * torque);
    const double s2 = dot(v_new, v_new);
    if (!(s2 <= st.max_speed2)) {  // also true for NaN
      if (!std::isfinite(s2) && st.bad_particle < 0) st.bad_particle = p.id[i];
      st.max_speed2 = std::isfinite(st.max_speed2) ? s2 : st.max_speed2;
    }
  }
  return st;
}

}  // namespace cgd::dem
