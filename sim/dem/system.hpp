#pragma once
// DemSystem: one rank's share of a soft-sphere DEM run -- particles, slab decomposition, ghosts,
// neighbour list with contact history, and the time step. The run loop (sim/run.hpp) drives it:
//   prepare()  refresh ghosts, or rebuild (wrap, migrate, sort, ghosts, list) when due
//   advance()  fused force + leapfrog pass into the next-state buffers
//   [output of step n from both buffers: x_n and v_n = (v_{n-1/2} + v_{n+1/2})/2]
//   commit()   swap buffers, reduce the displacement bound, detect blow-ups
#include <mpi.h>

#include <array>
#include <cstdint>
#include <vector>

#include "core/timers.hpp"
#include "sim/dem/comm.hpp"
#include "sim/dem/contact.hpp"
#include "sim/dem/integrator.hpp"
#include "sim/dem/neighbor.hpp"
#include "sim/dem/particles.hpp"

namespace cgd::dem {

struct DemSettings {
  std::array<double, 3> box_m{};
  double diameter_m = 0;       // collision diameter (parcel diameter)
  double mass_kg = 0;          // per particle (parcel)
  double dt_s = 0;
  bool contacts = true;
  bool friction = true;        // tangential history and rotation
  ContactParams contact;
  double skin_m = 0;
  UniformDrive drive;          // gravity/buoyancy and quiescent drag
  bool per_particle_drive = false;  // coupled runs: particles().a_ext replaces `drive`
  double overlap_limit = 0.25; // relative overlap (of the diameter) taken as a blow-up
  std::int64_t sort_interval_steps = 1000;
  std::vector<double> slab_lower_bounds;  // empty: equal slabs; else one per rank (fluid grid rows)
};

/// Global diagnostics of step n (reduced over ranks), from the synchronous velocities.
struct Diagnostics {
  double kinetic_translational_J = 0, kinetic_rotational_J = 0, contact_energy_J = 0;
  std::array<double, 3> momentum{}, velocity_mean{}, angular_momentum_spin{}, angular_momentum_orbital{};
  double contacts = 0;           // touching pairs
  double max_overlap_rel = 0;    // of the diameter
  std::int64_t particles = 0;
};

class DemSystem {
 public:
  DemSystem(const DemSettings& settings, MPI_Comm comm);
  // The ghost exchange holds a reference to this object's slab decomposition: not copyable/movable.
  DemSystem(const DemSystem&) = delete;
  DemSystem& operator=(const DemSystem&) = delete;

  /// Give this rank its owned particles (ids, positions, velocities, angular velocities or empty).
  /// Particles outside the slab are moved to their owner at the first rebuild.
  void set_particles(std::vector<std::int64_t> ids, std::vector<double> x, std::vector<double> v,
                     std::vector<double> w);
  /// Restart: also restore the contact store and the rebuild state, so that the run continues
  /// exactly as it would have without interruption.
  void restore(ContactStore store, double displacement_bound, bool rebuild_due, std::int64_t step,
               std::int64_t last_sort_step);

  void prepare();
  void advance();
  void commit();
  void step() {
    prepare();
    advance();
    commit();
  }

  /// Diagnostics of step n (collective). `synchronous`: between advance() and commit(), from the
  /// synchronous velocities v_n; otherwise at a step boundary, from the leapfrog velocities v_{n-1/2}.
  Diagnostics diagnostics(bool synchronous = true) const;
  /// Between advance() and commit(): synchronous velocities of the owned particles (3 per particle).
  std::vector<double> synchronous_velocity() const;
  std::vector<double> synchronous_angular_velocity() const;
  /// Contact store of the current list (for checkpoints; valid at the top of a step).
  ContactStore contact_store() const;

  const Particles& particles() const { return p_; }
  Particles& particles() { return p_; }
  const DemSettings& settings() const { return s_; }
  const SlabDecomposition& slabs() const { return slabs_; }
  std::int64_t step_index() const { return step_; }
  double displacement_bound() const { return displacement_bound_; }
  bool rebuild_due() const { return rebuild_due_; }
  std::int64_t last_sort_step() const { return last_sort_step_; }
  std::int64_t rebuilds() const { return rebuilds_; }
  void set_rebuilds(std::int64_t n) { rebuilds_ = n; }  // restart: the counter continues
  /// Largest overlap / diameter over all ranks at the last committed step.
  double last_max_overlap_rel() const { return last_max_overlap_rel_; }
  std::size_t neighbor_entries() const { return list_.entries(); }
  std::size_t ghosts() const { return ghosts_.ghosts(); }
  std::size_t bytes() const;
  double cutoff() const { return s_.diameter_m + s_.skin_m; }

  PhaseTimers& timers() { return timers_; }
  const PhaseTimers& timers() const { return timers_; }

 private:
  void full_rebuild();
  void build_ghosts_and_list();

  DemSettings s_;
  SlabDecomposition slabs_;
  GhostExchange ghosts_;
  Particles p_;
  NeighborList list_;
  ContactStore store_;
  KernelConstants kc_;
  KernelStats last_stats_;
  std::int64_t step_ = 0, last_sort_step_ = -1, rebuilds_ = 0;
  double displacement_bound_ = 0, last_max_overlap_rel_ = 0;
  bool rebuild_due_ = true, list_valid_ = false;
  PhaseTimers timers_;
  std::size_t t_neigh_, t_comm_, t_force_;
};

}  // namespace cgd::dem
