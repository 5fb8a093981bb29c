#pragma once
// DemSystem: one rank's share of a soft-sphere DEM run -- particles, slab decomposition, ghosts,
// neighbour list with contact history, and the time step. The run loop (sim/run.hpp) drives it:
//   prepare()  refresh ghosts, or rebuild (wrap, migrate, sort, ghosts, list) when due
//   advance()  force pass: the force on every particle with neighbours (integrator.hpp)
//   [output of step n: x_n and v_n = (v_{n-1/2} + v_{n+1/2})/2, v_{n+1/2} formed from the forces]
//   commit()   integration pass in place, reduce the displacement bound, detect blow-ups
//
// Free flight (issue 17). In a dilute suspension most particles have an empty neighbour list: nothing
// can touch them before the next rebuild, and their step is the drive's kick and a drift. They are
// not moved every step: they wait (`dormant_`) and are brought up to date -- the same kick_drift, once
// per step missed, so bit for bit what the integration pass would have done -- whenever anything looks
// at them: before a rebuild, at particles() (a fluid-step boundary: the coupler reads and writes them),
// diagnostics, output and checkpoints. A particle stays in the integration pass when a list on any rank
// refers to it (GhostExchange::restrict_forward), and its ghosts are then the only ones forwarded.
// The rebuild criterion needs each step's largest speed exactly (it decides the steps of the wraps):
// a waiting particle's speed after k steps lies within |v_0| -+ k dt |a|, so over a horizon of
// kHorizon steps only the few whose upper bound reaches the largest lower bound can hold the maximum;
// those (`candidates`) are integrated every step with the others, so the maximum is the one the plain
// pass finds, and rebuilds, wraps and trajectories are those of integrating everyone every step.
// The drive may depend on the velocity (the quiescent fluid's linear drag): the bound on |a| then uses
// the drag's contraction (select_free_flight).
#include <mpi.h>

#include <algorithm>
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
  double skin_m = 0;               // fixed skin; with skin_target_steps > 0 the first list's skin
  // Adaptive skin (skin_target_steps > 0): at each full rebuild the skin is set to 2 v_max dt target steps
  // (v_max the fastest particle's speed at the last step, the same on every rank), so that a list lasts about
  // that many steps, clamped to [skin_min_m, skin_max_m] and to what the thinnest slab allows. The list only
  // needs to hold every pair that can touch before the next rebuild; which extra pairs it holds and when it
  // is rebuilt change no trajectory (neighbor.hpp), so the skin is free to follow the flow.
  std::int64_t skin_target_steps = 0;
  double skin_min_m = 0, skin_max_m = 0;
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
  /// Between advance() and commit(): the half-step velocities v_{n+1/2} (w_{n+1/2}) commit() will give
  /// the owned particles, in the current order (3 per particle; angular: empty without rotation).
  std::vector<double> next_velocity() const;
  std::vector<double> next_angular_velocity() const;
  /// Contact store of the current list (for checkpoints; valid at the top of a step).
  ContactStore contact_store() const;

  /// The particles, every one at the current step (particles in free flight are brought up to date).
  /// The non-const access may change the drive (a_ext): free flight then restarts from the new one.
  const Particles& particles() const {
    catch_up();
    return p_;
  }
  Particles& particles() {
    catch_up();
    selection_due_ = true;
    return p_;
  }
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
  /// Owned particles in free flight (not integrated every step) and integrated every step, at the last step.
  std::size_t free_flight_particles() const { return dormant_.size(); }
  std::size_t integrated_particles() const { return integrate_.size(); }
  std::size_t ghosts() const { return ghosts_.ghosts(); }
  std::size_t bytes() const;
  double cutoff() const { return s_.diameter_m + skin_m_; }
  /// The skin of the current list (fixed, or the adaptive skin of the last build).
  double skin() const { return skin_m_; }
  /// Restart: the skin the checkpointed list was built with (its displacement bound is against it).
  void set_skin(double skin_m) { skin_m_ = std::clamp(skin_m, skin_min_m_, skin_max_m_); }

  PhaseTimers& timers() { return timers_; }
  const PhaseTimers& timers() const { return timers_; }

 private:
  void full_rebuild();
  void build_ghosts_and_list();
  /// After a list build (nullptr: no contacts): the rows with neighbours, the particles some list refers
  /// to (and the ghosts forward() keeps), zero forces; a new free-flight selection is due.
  void classify(const NeighborList* list);
  /// Brings the particles in free flight to the current step (kick_drift once per step missed).
  void catch_up() const;
  /// Splits the particles without list references into candidates (integrated every step) and the
  /// ones in free flight, from their velocities and drive now (see the header).
  void select_free_flight();
  template <class F>
  void with_drive(F&& f) const;

  DemSettings s_;
  SlabDecomposition slabs_;
  GhostExchange ghosts_;
  // mutable: the particles in free flight are brought up to date (catch_up) by const accessors
  mutable Particles p_;
  NeighborList list_;
  ContactStore store_;
  KernelConstants kc_;
  KernelStats last_stats_;
  std::int64_t step_ = 0, last_sort_step_ = -1, rebuilds_ = 0;
  double displacement_bound_ = 0, last_max_overlap_rel_ = 0;
  double skin_m_ = 0, skin_min_m_ = 0, skin_max_m_ = 0;  // current skin; adaptive bounds (fixed: all equal)
  double last_max_speed_ = 0;                            // fastest particle at the last step (all ranks)
  bool rebuild_due_ = true, list_valid_ = false;
  // the split step (integrator.hpp): forces of the particles with neighbours, stored between advance()
  // and commit(), zero for the others; free flight
  static constexpr std::int64_t kHorizon = 100;      // steps a selection of candidates holds
  std::vector<double> force_, torque_;               // 3 per row of force_rows_ (not per particle)
  std::vector<std::int32_t> force_rows_;             // owned particles with a non-empty list
  std::vector<char> referenced_;                     // per owned: a list (any rank) refers to it or has one
  std::vector<std::int32_t> integrate_;              // integrated every step (increasing)
  mutable std::vector<std::int32_t> dormant_;        // in free flight (increasing)
  mutable std::int64_t dormant_step_ = 0;            // the step the particles in free flight are at
  std::int64_t selection_step_ = 0;
  bool selection_due_ = true;
  bool free_flight_ = false;                         // the drive allows it
  PhaseTimers timers_;
  std::size_t t_neigh_, t_comm_, t_force_;
};

}  // namespace cgd::dem
