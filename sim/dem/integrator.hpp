#pragma once
// The DEM step in two passes over the particles' one state (issue 17; it was one fused pass into a
// second state buffer):
//   1. forces   a flat pass over the neighbour-list entries of the particles that have any, with the
//               partners' positions prefetched a few entries ahead and the rows' positions a few rows
//               ahead (both were the pass's cache misses; velocities and spins are read only where a
//               pair touches, which few list entries do); each particle's force (and torque) is summed
//               in its list's canonical order and stored per row, one sequential stream. With friction
//               the touching entries are gathered in batches and the law is evaluated four at a time
//               (AVX2), bit for bit the scalar law (compute_forces_batched, issue 25);
//   2. integrate a pass, in place, over the particles that must move this step (their state prefetched
//               a few ahead; a particle's force is the next row's when it is that row, else zero): leapfrog
//               (kick-drift, symplectic, second order)
//     v_{n+1/2} = v_{n-1/2} + dt a_n,   x_{n+1} = x_n + dt v_{n+1/2},   w_{n+1/2} = w_{n-1/2} + dt T_n / I,
//               with a_n = F_n/m + a_ext(v_{n-1/2}).
// Velocity-dependent forces (dashpots, drag) use v_{n-1/2}, the same half-step lag as LAMMPS' velocity
// Verlet. The contact model and the external forces are template parameters: an effect that is off
// generates no code in the loop. `kick_drift` is the one expression of a step's arithmetic: the
// integration pass, the free flight of particles without neighbours (DemSystem) and the velocities
// formed for output all call it, so a particle moved in free flight over n steps gets exactly the n
// kicks and drifts the integration pass would have given it, bit for bit.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
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
  std::nullptr_t prefetch_base() const { return nullptr; }  // nothing per particle to prefetch
};

/// Per-particle external acceleration, constant over the DEM sub-steps of a fluid step (coupled runs:
/// drag from the fluid, pressure-gradient force, gravity and the periodic driving; sim/coupling).
struct PerParticleDrive {
  const double* accel = nullptr;  // 3 per owned particle
  inline V3 operator()(std::size_t i, V3) const { return load3(accel + 3 * i); }
  const double* prefetch_base() const { return accel; }
};

struct KernelStats {
  double max_speed2 = 0;      // max |v_{n+1/2}|^2 (NaN if any velocity is NaN)
  double max_overlap = 0;     // m
  std::int64_t overlap_particle = -1, overlap_partner = -1;
  std::int64_t bad_particle = -1;  // first particle with a non-finite velocity
  bool left_reach = false;         // a particle moved further from its anchor than its reach (DemSystem)
};

struct KernelConstants {
  double dt = 0, radius = 0, inv_mass = 0, inv_inertia = 0;
};

/// v_{n+1/2} of particle i from its force f (zero without contacts) and the drive.
template <class Drive>
inline V3 kicked_velocity(std::size_t i, V3 v, V3 f, const Drive& drive, const KernelConstants& k) {
  const V3 a = k.inv_mass * f + drive(i, v);
  return v + k.dt * a;
}

/// One step of particle i in place: kick, then drift. Returns |v_{n+1/2}|^2.
template <class Drive>
inline double kick_drift(std::size_t i, double* x, double* v, V3 f, const Drive& drive, const KernelConstants& k) {
  const V3 v_new = kicked_velocity(i, load3(v), f, drive, k);
  store3(v, v_new);
  store3(x, load3(x) + k.dt * v_new);
  return dot(v_new, v_new);
}

/// w_{n+1/2} from the torque.
inline V3 kicked_spin(V3 w, V3 torque, const KernelConstants& k) { return w + (k.dt * k.inv_inertia) * torque; }

/// Prefetch distances of the force passes. In list entries: entries are contiguous over rows (CSR), so the
/// look-ahead runs on into the next particles' lists. 32 (issue 17, third round): in the Table 1 box's own
/// developed state (~1.2 entries per particle, lists of a 0.25 d skin) 8 left the partner's position a cache
/// miss (force pass 17-19 -> 14.2-14.8 ns per particle-step; 64: no better). In rows: the row's own position.
/// The three helpers below are [[gnu::always_inline]]: left to GCC 12's judgement they stayed out of line in the
/// batched pass, whose force + integrate in the 0.30 plug then took 66 instead of 55 ns per particle-step.
inline constexpr std::int64_t kForceEntryAhead = 32;
inline constexpr std::size_t kForceRowAhead = 4;

/// The force passes' look-ahead at row r: the position of the particle kForceRowAhead rows on.
[[gnu::always_inline]] inline void prefetch_row_ahead(const std::int32_t* rows, std::size_t r, std::size_t n_rows, const double* x) {
  if (r + kForceRowAhead < n_rows) {
    const std::size_t ia = 3 * static_cast<std::size_t>(rows[r + kForceRowAhead]);
    __builtin_prefetch(x + ia);
    __builtin_prefetch(x + ia + 2);
  }
}

/// The force passes' look-ahead at list entry e: the partner's position of the entry kForceEntryAhead on; with
/// friction, where that entry is flagged (it touched at a recent step and most likely touches now), also its
/// spring (no longer part of a stream the hardware follows) and the partner's velocity and spin, which the law
/// reads. Velocities and spins of entries that do not touch are not needed, and few do.
template <bool kFriction>
[[gnu::always_inline]] inline void prefetch_entry_ahead(const std::int32_t* index, std::int64_t e, std::int64_t n_entries, const double* x,
                                 const double* v, const double* w, const double* spring) {
  if (e + kForceEntryAhead >= n_entries) return;
  const std::int32_t raw_n = index[e + kForceEntryAhead];
  const std::int32_t jn = raw_n & NeighborList::kPartnerMask;
  __builtin_prefetch(x + 3 * jn);
  __builtin_prefetch(x + 3 * jn + 2);
  if constexpr (kFriction) {
    if (NeighborList::spring_flagged(raw_n)) {
      const double* s = spring + 3 * (e + kForceEntryAhead);
      __builtin_prefetch(s);
      __builtin_prefetch(s + 2);
      __builtin_prefetch(v + 3 * jn);
      __builtin_prefetch(v + 3 * jn + 2);
      __builtin_prefetch(w + 3 * jn);
      __builtin_prefetch(w + 3 * jn + 2);
    }
  }
}

/// A flagged entry (partner j) that no longer touches: its history goes with the contact. Only a flagged
/// entry's spring can be other than +0.0 (neighbor.hpp), so the entries that never touch read no spring at all
/// (issue 25, third round); this one is set to +0.0 (a -0.0 too) and its flag cleared.
[[gnu::always_inline]] inline void end_contact(std::int32_t* index, double* spring, std::int64_t e, std::int32_t j) {
  double* s = spring + 3 * e;
  s[0] = s[1] = s[2] = 0.0;
  index[e] = j;
}

/// Pass 1, entry by entry: the force (and torque) on each particle of `rows` (particles with a non-empty
/// list) from its list, in the list's order, into force[3 r..] (torque[3 r..] with friction) for row r: the
/// forces are stored per row, a sequential stream, not per particle. Updates the tangential histories and
/// the overlap statistics. `compute_forces` (below) uses it for the frictionless law; for the frictional one
/// it is the reference the batched pass is tested against, bit for bit.
template <class Contact>
void compute_forces_per_entry(const Particles& p, NeighborList& list, const Contact& contact, const KernelConstants& k,
                    const std::int32_t* rows, std::size_t n_rows, double* __restrict force,
                    double* __restrict torque_out, KernelStats& st) {
  constexpr bool kFriction = std::is_same_v<Contact, SpringDashpot<true>>;
  const double contact_dist = 2.0 * k.radius, contact_dist2 = contact_dist * contact_dist;
  const double* __restrict x = p.x.data();
  const double* __restrict v = p.v.data();
  const double* __restrict w = kFriction ? p.w.data() : nullptr;
  const std::int64_t* __restrict offset = list.offset.data();
  std::int32_t* __restrict index = list.index.data();  // the partner, and the spring's flag (neighbor.hpp)
  double* __restrict spring = kFriction ? list.xi.data() : nullptr;
  constexpr std::int32_t kMask = NeighborList::kPartnerMask;
  const std::int64_t n_entries = static_cast<std::int64_t>(list.index.size());
  for (std::size_t r = 0; r < n_rows; ++r) {
    const std::size_t i = static_cast<std::size_t>(rows[r]);
    prefetch_row_ahead(rows, r, n_rows, x);
    const V3 xi = load3(x + 3 * i);
    V3 f{0, 0, 0};
    V3 torque{0, 0, 0};
    const std::int64_t k0 = offset[i], k1 = offset[i + 1];
    for (std::int64_t e = k0; e < k1; ++e) {
      prefetch_entry_ahead<kFriction>(index, e, n_entries, x, v, w, spring);
      const std::int32_t raw = index[e];
      const std::int32_t j = raw & kMask;
      const V3 dx = xi - load3(x + 3 * j);
      const double r2 = dot(dx, dx);
      if (r2 >= contact_dist2) {
        if constexpr (kFriction)
          if (NeighborList::spring_flagged(raw)) end_contact(index, spring, e, j);
        continue;
      }
      // touching: its spring becomes what the law makes of it (flagged: it may be non-zero from now on)
      if constexpr (kFriction)
        if (!NeighborList::spring_flagged(raw))
          index[e] = NeighborList::with_spring_flag(raw);
      const double rr = std::sqrt(r2);
      const double overlap = contact_dist - rr;
      if (overlap > st.max_overlap) {
        st.max_overlap = overlap;
        st.overlap_particle = p.id[i];
        st.overlap_partner = p.id[j];
      }
      // the row's own velocity and spin only where it touches (most rows touch nothing)
      const V3 dv = load3(v + 3 * i) - load3(v + 3 * j);
      if constexpr (kFriction) {
        f = f + contact.force(dx, rr, overlap, dv, load3(w + 3 * i), load3(w + 3 * j), k.radius, k.radius, spring + 3 * e, torque);
      } else {
        f = f + contact.normal_force(dx, rr, overlap, dv);
      }
    }
    store3(force + 3 * r, f);
    if constexpr (kFriction) store3(torque_out + 3 * r, torque);
  }
}

/// Pass 1 with friction, the contact law evaluated in batches (issue 25): the same pass over the rows and
/// their entries as `compute_forces_per_entry` (the same distance test, spring flags, zeroed springs and
/// prefetches), in three steps per batch of touching entries:
///   1. scan: each entry's dx, r2, partner and row go into the batch's next slot, and the slot is kept
///      (the batch's count advances) only where the pair touches -- no branch on the test, whose outcome
///      is as good as random in a dense state; the spring flags change under a branch only where a contact
///      starts or ends (rare);
///   2. when the batch is full (and after the last row) the gather: each kept entry's velocities, spins
///      and spring, loads that no longer wait behind one another's branches;
///   3. `SpringDashpot<true>::force_batch` evaluates the law over the batch, four entries per instruction,
///      and the results are taken in the batch's order, which is the list's: the overlap statistic (the
///      first largest overlap), each entry's force and torque added to its row's sums, its new spring
///      written back.
/// A row's sums start at +0.0 in the output arrays when the row is reached and may be added to over
/// several batches (a row with more touching entries than a batch holds): the same additions in the same
/// order as the per-entry pass's register sums, so force, torque, springs, flags and statistics are bit for
/// bit those of `compute_forces_per_entry` (tests/unit/test_dem_batched_forces.cpp).
template <std::size_t kBatch = 32>
void compute_forces_batched(const Particles& p, NeighborList& list, const SpringDashpot<true>& contact,
                            const KernelConstants& k, const std::int32_t* rows, std::size_t n_rows,
                            double* __restrict force, double* __restrict torque_out, KernelStats& st) {
  const double contact_dist = 2.0 * k.radius, contact_dist2 = contact_dist * contact_dist;
  const double* __restrict x = p.x.data();
  const double* __restrict v = p.v.data();
  const double* __restrict w = p.w.data();
  const std::int64_t* __restrict offset = list.offset.data();
  std::int32_t* __restrict index = list.index.data();
  double* __restrict spring = list.xi.data();
  constexpr std::int32_t kMask = NeighborList::kPartnerMask;
  const std::int64_t n_entries = static_cast<std::int64_t>(list.index.size());
  FrictionBatch<kBatch> batch;
  const auto flush = [&] {
    for (std::size_t b = 0; b < batch.count; ++b) {  // the gather
      const std::size_t i = static_cast<std::size_t>(batch.i[b]), j = static_cast<std::size_t>(batch.j[b]);
      const V3 dv = load3(v + 3 * i) - load3(v + 3 * j);
      const V3 wi = load3(w + 3 * i), wj = load3(w + 3 * j), s = load3(spring + 3 * batch.entry[b]);
      batch.dv[0][b] = dv.x, batch.dv[1][b] = dv.y, batch.dv[2][b] = dv.z;
      batch.wi[0][b] = wi.x, batch.wi[1][b] = wi.y, batch.wi[2][b] = wi.z;
      batch.wj[0][b] = wj.x, batch.wj[1][b] = wj.y, batch.wj[2][b] = wj.z;
      batch.xi[0][b] = s.x, batch.xi[1][b] = s.y, batch.xi[2][b] = s.z;
    }
    contact.force_batch(batch, contact_dist, k.radius);
    for (std::size_t b = 0; b < batch.count; ++b) {  // the results, in list order
      if (batch.overlap[b] > st.max_overlap) {
        st.max_overlap = batch.overlap[b];
        st.overlap_particle = p.id[batch.i[b]];
        st.overlap_partner = p.id[batch.j[b]];
      }
      double* fr = force + 3 * static_cast<std::size_t>(batch.row[b]);
      double* tr = torque_out + 3 * static_cast<std::size_t>(batch.row[b]);
      double* s = spring + 3 * batch.entry[b];
      for (int c = 0; c < 3; ++c) {
        fr[c] = fr[c] + batch.f[c][b];
        tr[c] = tr[c] + batch.t[c][b];
        s[c] = batch.xi[c][b];
      }
    }
    batch.count = 0;
  };
  for (std::size_t r = 0; r < n_rows; ++r) {
    const std::size_t i = static_cast<std::size_t>(rows[r]);
    prefetch_row_ahead(rows, r, n_rows, x);
    const V3 xi = load3(x + 3 * i);
    store3(force + 3 * r, V3{0, 0, 0});
    store3(torque_out + 3 * r, V3{0, 0, 0});
    const std::int64_t k0 = offset[i], k1 = offset[i + 1];
    for (std::int64_t e = k0; e < k1; ++e) {
      prefetch_entry_ahead<true>(index, e, n_entries, x, v, w, spring);
      const std::int32_t raw = index[e];
      const std::int32_t j = raw & kMask;
      const V3 dx = xi - load3(x + 3 * j);
      const double r2 = dot(dx, dx);
      const bool touching = !(r2 >= contact_dist2);  // as compute_forces_per_entry's test (a NaN touches)
      if (touching != NeighborList::spring_flagged(raw)) {
        if (touching)
          index[e] = NeighborList::with_spring_flag(raw);  // its spring may be non-zero from now on
        else
          end_contact(index, spring, e, j);
      }
      const std::size_t b = batch.count;  // < kBatch: a full batch is flushed at once
      batch.entry[b] = e;
      batch.row[b] = static_cast<std::int32_t>(r);
      batch.i[b] = static_cast<std::int32_t>(i);
      batch.j[b] = j;
      batch.r2[b] = r2;
      batch.dx[0][b] = dx.x, batch.dx[1][b] = dx.y, batch.dx[2][b] = dx.z;
      batch.count = b + touching;
      if (batch.count == kBatch) flush();
    }
  }
  if (batch.count > 0) flush();
}

/// Pass 1: `compute_forces_batched` for the frictional law, `compute_forces_per_entry` for the others.
template <class Contact>
void compute_forces(const Particles& p, NeighborList& list, const Contact& contact, const KernelConstants& k,
                    const std::int32_t* rows, std::size_t n_rows, double* __restrict force,
                    double* __restrict torque_out, KernelStats& st) {
  if constexpr (std::is_same_v<Contact, SpringDashpot<true>>)
    compute_forces_batched(p, list, contact, k, rows, n_rows, force, torque_out, st);
  else
    compute_forces_per_entry(p, list, contact, k, rows, n_rows, force, torque_out, st);
}

/// Pass 2: kick and drift the particles of `idx` in place from the forces of pass 1 (per row: `rows`, a
/// subsequence of `idx`, both increasing; zero for a particle whose list is empty) and the drive; spins
/// from the torques. Records the largest speed, the first non-finite velocity, and whether a particle's new
/// position lies further from its anchor (x, y, z, reach: 4 floats per particle) than its reach.
template <class Drive>
void integrate(Particles& p, const double* __restrict force, const double* __restrict torque, const Drive& drive,
               const KernelConstants& k, const std::int32_t* idx, std::size_t n, const std::int32_t* rows,
               std::size_t n_rows, const float* __restrict anchor, KernelStats& st) {
  double* __restrict x = p.x.data();
  double* __restrict v = p.v.data();
  double* __restrict w = p.rotation ? p.w.data() : nullptr;
  const V3 zero{0, 0, 0};
  constexpr std::size_t kAhead = 8;
  std::size_t r = 0;
  for (std::size_t m = 0; m < n; ++m) {
    const std::size_t i = static_cast<std::size_t>(idx[m]);
    if (m + kAhead < n) {  // the state of a particle a few ahead (both ends of its 24 bytes)
      const std::size_t ia = 3 * static_cast<std::size_t>(idx[m + kAhead]);
      __builtin_prefetch(x + ia);
      __builtin_prefetch(x + ia + 2);
      __builtin_prefetch(v + ia);
      __builtin_prefetch(v + ia + 2);
      if constexpr (!std::is_same_v<decltype(drive.prefetch_base()), std::nullptr_t>) {
        __builtin_prefetch(drive.prefetch_base() + ia);
        __builtin_prefetch(drive.prefetch_base() + ia + 2);
      }
      if (w) {
        __builtin_prefetch(w + ia);
        __builtin_prefetch(w + ia + 2);
      }
      __builtin_prefetch(anchor + 4 * static_cast<std::size_t>(idx[m + kAhead]));
    }
    // a particle without a list has no force: the zero the force array used to hold for it
    const bool has_force = r < n_rows && static_cast<std::size_t>(rows[r]) == i;
    const V3 f = has_force ? load3(force + 3 * r) : zero;
    const double s2 = kick_drift(i, x + 3 * i, v + 3 * i, f, drive, k);
    if (w) store3(w + 3 * i, kicked_spin(load3(w + 3 * i), has_force ? load3(torque + 3 * r) : zero, k));
    r += has_force;
    {
      const float* a = anchor + 4 * i;
      const V3 dx = load3(x + 3 * i) - V3{a[0], a[1], a[2]};
      const double reach = a[3];
      st.left_reach |= !(dot(dx, dx) <= reach * reach);  // NaN too
    }
    if (!(s2 <= st.max_speed2)) {  // also true for NaN
      if (!std::isfinite(s2) && st.bad_particle < 0) st.bad_particle = p.id[i];
      st.max_speed2 = std::isfinite(st.max_speed2) ? s2 : st.max_speed2;
    }
  }
}

}  // namespace cgd::dem
