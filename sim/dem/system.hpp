#pragma once
// DemSystem: one rank's share of a soft-sphere DEM run -- particles, slab decomposition, ghosts,
// neighbour list with contact history, and the time step. The run loop (sim/run.hpp) drives it:
//   prepare()  refresh ghosts, or rebuild (wrap, balance the slabs (DemSettings::balance_slabs), migrate, sort,
//              ghosts, list) when due
//   advance()  force pass: the force on every particle with neighbours (integrator.hpp)
//   [output of step n: x_n and v_n = (v_{n-1/2} + v_{n+1/2})/2, v_{n+1/2} formed from the forces]
//   commit()   integration pass in place (each particle checked against its anchor's reach), detect blow-ups
//
// Neighbour lists (issue 25): each particle carries its own half-skin h_i, set at every full rebuild from
// its own speed (DemSettings: h_i = target steps x dt x |v_i|, clamped; a fixed skin gives every particle
// h = skin / 2), and the list holds the pairs closer than d + h_i + h_j (neighbor.hpp). It stays valid while
// no particle has moved more than its own h_i from where it was at the build (its anchor), so the list is
// rebuilt when one has: an exact, per-particle predicate (integrated particles are checked every step in the
// integration pass, particles in free flight by a bound, below), the same on every rank count and across a
// restart (the anchors are checkpointed), so rebuilds -- and the wraps into the box they do, which change
// round-off -- happen at the same steps. In a dense suspension the slow majority no longer carries the
// skin of the one fastest particle (the global skin of before: 6.6 list entries per particle at <phi> = 0.20
// in a gas channel, 2.7 with skins per particle).
//
// Free flight (issue 17). In a dilute suspension most particles have an empty neighbour list: nothing
// can touch them before the next rebuild, and their step is the drive's kick and a drift. They are
// not moved every step: they wait (`dormant_`) and are brought up to date -- the same kick_drift, once
// per step missed, so bit for bit what the integration pass would have done -- whenever anything looks
// at them: before a rebuild, at particles() (a fluid-step boundary: the coupler reads and writes them),
// diagnostics, output and checkpoints. A particle stays in the integration pass when a list on any rank
// refers to it (GhostExchange::restrict_forward), and its ghosts are then the only ones forwarded.
// A waiting particle's speed after k <= kHorizon steps lies within |v_0| + k dt |a|, which bounds how far it
// can drift: it waits only while that bound keeps it within its anchor's reach, and the selection is renewed
// before the first waiting particle could leave it (select_free_flight), so the rebuild predicate needs no
// look at the waiting particles. The drive may depend on the velocity (the quiescent fluid's linear drag): the
// bound on |a| then uses the drag's contraction.
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
  double skin_m = 0;               // fixed skin (a pair's: h_i + h_j); ignored with skin_target_steps > 0
  // Adaptive skins (skin_target_steps > 0): at each full rebuild each particle's half-skin is set to
  // dt x target steps x its own speed, so that it would take about that many steps to use it up, clamped to
  // [skin_min_m / 2, skin_max_m / 2] (and to what the thinnest slab allows). The list only needs to hold every
  // pair that can touch before the next rebuild; which extra pairs it holds changes no trajectory
  // (neighbor.hpp), so the skins are free to follow the flow.
  std::int64_t skin_target_steps = 0;
  double skin_min_m = 0, skin_max_m = 0;
  UniformDrive drive;          // gravity/buoyancy and quiescent drag
  bool per_particle_drive = false;  // coupled runs: particles().a_ext replaces `drive`
  double overlap_limit = 0.25; // relative overlap (of the diameter) taken as a blow-up
  std::int64_t sort_interval_steps = 1000;
  std::vector<double> slab_lower_bounds;  // the first slabs: empty, equal slabs; else one lower bound per rank
  // Balanced slabs (issue 25; the run driver's choice): at each full rebuild, before the migration, the slabs'
  // bounds are set so that every rank has about as much work: quantiles of a global histogram of y in which each
  // particle weighs 1 + 4 (m - 1), m the particles of its rank in its cell of a coarse grid of cells one cutoff
  // (d + the largest pair skin allowed) wide -- its expected list entries, a sphere of the cutoff holding about 4
  // cells. Each slab at least min(d + 2 x the largest pair skin allowed, L_y / ranks) high (the ghost shell, also of
  // a restart between rebuilds). The trajectories do not depend on the bounds (newton off, sums in partner-id
  // order): bit for bit the same at any rank count, with or without balancing. The coupled results are not: each
  // rank's share of the deposit sums depends on which particles it owns, so the bounds are a function of the
  // positions at the rebuild alone (not of the lists, whose first build after a restart is wider), and a restart
  // that restores the bounds in force reproduces them at every later rebuild. false: the first slabs stay.
  bool balance_slabs = false;
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
  /// Restart: also restore the contact store and the rebuild state (the anchors of the last list build: 4
  /// floats per owned particle, in the order of set_particles; empty forces a rebuild at the first step), so
  /// that the run continues exactly as it would have without interruption.
  void restore(ContactStore store, std::vector<float> anchors, bool rebuild_due, std::int64_t step,
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
  /// The lower y bound of every rank's slab in force (a checkpoint keeps them: a restart between rebuilds
  /// needs the slabs its particles and anchors belong to).
  const std::vector<double>& slab_bounds() const { return slabs_.lower_bounds(); }
  /// Restart at the checkpoint's rank count: the slabs in force when it was written (before set_particles).
  /// InputError if a slab is thinner than the contact cutoff.
  void set_slab_bounds(const std::vector<double>& lower_bounds);
  std::int64_t step_index() const { return step_; }
  /// Per owned particle: its position at the last full rebuild and how far it may move from it before the
  /// list must be rebuilt (x, y, z, reach; m, as floats, rounded so that the predicate stays conservative).
  const std::vector<float>& anchors() const { return anchor_; }
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
  /// The largest pair distance the current list can hold (the binning's cell size, the ghost shell).
  double cutoff() const { return s_.diameter_m + skin_m_; }
  /// The largest pair skin of the last full rebuild (2 x the largest half-skin; fixed: the skin).
  double skin() const { return skin_m_; }
  /// Restart: the skin of the checkpointed list's build (its anchors' reaches are within half of it).
  void set_skin(double skin_m) { skin_m_ = std::clamp(skin_m, skin_min_m_, skin_max_m_); }

  PhaseTimers& timers() { return timers_; }
  const PhaseTimers& timers() const { return timers_; }

 private:
  void full_rebuild();
  /// balance_slabs: new slab bounds from the owned particles' (wrapped) heights, the same on every rank. Collective.
  void balance_slabs();
  static constexpr int kBalanceBins = 4096;  // of the histogram of y (the bound within a bin is interpolated)
  static constexpr double kBalanceCells = 1 << 22;  // at most, of the coarse grid that weights the particles
  /// Ghosts and list; `mid_interval` (a restart between rebuilds): every particle may already have moved up to
  /// its reach from its anchor, so the pairs are listed at d + 2 skin (each side 2 x the largest half-skin).
  void build_ghosts_and_list(bool mid_interval);
  /// A particle's half-skin for its speed (fixed skin: half of it).
  double half_skin(double speed) const;
  /// Anchors of the owned particles at a full rebuild (their positions and reaches now) and, with contacts,
  /// their half-skins for the list build; returns this rank's largest half-skin.
  double set_anchors();
  /// After a list build (nullptr: no contacts): the rows with neighbours, the particles some list refers
  /// to (and the ghosts forward() keeps), zero forces; a new free-flight selection is due.
  void classify(const NeighborList* list);
  /// Brings the particles in free flight to the current step (kick_drift once per step missed).
  void catch_up() const;
  /// Splits the particles without list references into those integrated every step and the ones in free
  /// flight, from their velocities, drive and anchors now (see the header).
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
  double last_max_overlap_rel_ = 0;
  double skin_m_ = 0, skin_min_m_ = 0, skin_max_m_ = 0;  // largest pair skin of the list; adaptive bounds
  double thinnest_slab_m_ = 0;                           // of all ranks (the ghost shell's limit)
  double min_slab_m_ = 0;                                // balance_slabs: no slab thinner than this
  double anchor_margin_m_ = 0;                           // covers the float rounding of an anchor
  std::vector<float> anchor_;                            // per owned particle: x, y, z at the build, reach
  std::vector<float> half_skin_;                         // per owned particle and ghost, for a list build
  bool rebuild_due_ = true, list_valid_ = false;
  // the split step (integrator.hpp): forces of the particles with neighbours, stored between advance()
  // and commit(), zero for the others; free flight
  static constexpr std::int64_t kHorizon = 100;      // steps a selection holds at most
  static constexpr std::int64_t kMinWait = 4;        // a particle waits only if it can for this many steps
  std::int64_t selection_horizon_ = kHorizon;        // steps the current selection holds
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
