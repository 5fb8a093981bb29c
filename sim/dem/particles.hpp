#pragma once
// Particle data of one rank as a structure of arrays (vectors interleaved xyz).
// Layout: owned particles [0, n_owned), then ghosts [n_owned, n_total) (periodic images and copies of
// neighbouring ranks' particles, refreshed every step). The kinematic state is held once and advanced
// in place: the force pass (sim/dem/integrator.hpp) reads (x, v, w) at step n and stores each force in
// DemSystem's force arrays, then a streaming pass kicks and drifts every particle to step n+1 (there is
// no second state buffer since issue 17: 72 B per particle and ghost less, and one write stream less).
// Velocities are the leapfrog half-step velocities v_{n-1/2}; the synchronous v_n = (v_{n-1/2} +
// v_{n+1/2})/2 is formed for output (DemSystem::synchronous_velocity).
#include <cstddef>
#include <cstdint>
#include <vector>

namespace cgd::dem {

struct Particles {
  std::size_t n_owned = 0;
  std::size_t n_total = 0;  // owned + ghosts
  bool rotation = false;    // angular velocity is simulated (friction > 0)
  bool external = false;    // a per-particle external acceleration is held (coupled runs)

  std::vector<std::int64_t> id;  // global id, n_total
  std::vector<double> x, v, w;   // state, 3 * n_total (w empty without rotation)
  std::vector<double> a_ext;     // external acceleration, 3 per particle (fluid forces, gravity), if external

  /// Resize for `owned` particles plus room for `total - owned` ghosts; keeps existing data.
  void resize(std::size_t owned, std::size_t total) {
    n_owned = owned;
    n_total = total;
    id.resize(total);
    x.resize(3 * total);
    v.resize(3 * total);
    if (rotation) w.resize(3 * total);
    if (external) a_ext.resize(3 * total);
  }
  /// Capacity for `total` particles (owned + ghosts) without the geometric over-allocation that
  /// growing one swap at a time would cause.
  void reserve(std::size_t total) {
    id.reserve(total);
    for (auto* f : {&x, &v}) f->reserve(3 * total);
    if (rotation) w.reserve(3 * total);
    if (external) a_ext.reserve(3 * total);
  }
  std::size_t bytes() const {
    return id.capacity() * sizeof(std::int64_t) +
           (x.capacity() + v.capacity() + w.capacity() + a_ext.capacity()) * sizeof(double);
  }
};

/// Contact history of owned particles keyed by partner id, in CSR form: the record that carries
/// the tangential spring across neighbour-list rebuilds, migration between ranks and restart.
/// Entry k of particle i: partner id `partner[k]`, spring xi[3k..3k+2] as seen from i.
struct ContactStore {
  std::vector<std::int64_t> offset{0};  // n_owned + 1
  std::vector<std::int64_t> partner;
  std::vector<double> xi;

  std::size_t contacts() const { return partner.size(); }
  void clear() {
    offset.assign(1, 0);
    partner.clear();
    xi.clear();
  }
};

}  // namespace cgd::dem
