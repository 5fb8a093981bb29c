#pragma once
// Slab decomposition along y (ARCHITECTURE.md "Parallel decomposition") and the ghost-particle exchange.
// Every rank owns the particles whose y lies in [y_lo, y_hi). The bounds may move between neighbour-list
// builds (DemSystem balances the particles over the ranks at each full rebuild, set_lower_bounds): ghosts
// and migration work for slabs of any height at least the ghost shell. Ghosts are built in three stages,
// x, z, then y, each stage taking as candidates everything that exists before it (owned + earlier
// ghosts), so edge and corner images come out right. x and z are always local periodic images; y goes
// to the neighbouring ranks (or is a local image with one rank). Between rebuilds `forward` refreshes
// the ghosts from their sources with the same periodic shifts, in the same order.
#include <mpi.h>

#include <array>
#include <cstdint>
#include <vector>

#include "sim/dem/particles.hpp"

namespace cgd::dem {

class SlabDecomposition {
 public:
  /// Equal slabs of the box height.
  SlabDecomposition(MPI_Comm comm, std::array<double, 3> box_m);
  /// Slabs with given lower bounds (one per rank, increasing, starting at 0, below the box height).
  SlabDecomposition(MPI_Comm comm, std::array<double, 3> box_m, const std::vector<double>& lower_bounds);
  /// New lower bounds (as the constructor's; RunError otherwise). The same on every rank; owned particles
  /// outside their new slab move at the next migrate().
  void set_lower_bounds(const std::vector<double>& lower_bounds);
  const std::vector<double>& lower_bounds() const { return lower_; }
  /// The thinnest slab's height, m.
  double thinnest() const;

  MPI_Comm comm() const { return comm_; }
  int rank() const { return rank_; }
  int size() const { return size_; }
  int down() const { return (rank_ + size_ - 1) % size_; }
  int up() const { return (rank_ + 1) % size_; }
  const std::array<double, 3>& box() const { return box_; }
  /// Lower y bound of rank r's slab (r = size gives the box height). Same arithmetic everywhere.
  double slab_lo(int r) const { return r == size_ ? box_[1] : lower_[r]; }
  double y_lo() const { return slab_lo(rank_); }
  double y_hi() const { return slab_lo(rank_ + 1); }
  /// The rank owning height y (y already wrapped into [0, L_y)).
  int owner(double y) const;
  /// Wrap a position into [0, L) in every dimension.
  void wrap(double* x) const;

 private:
  MPI_Comm comm_;
  int rank_ = 0, size_ = 1;
  std::array<double, 3> box_;
  std::vector<double> lower_;  // lower y bound of every rank's slab
};

class GhostExchange {
 public:
  explicit GhostExchange(const SlabDecomposition& slabs) : slabs_(slabs) {}

  /// Discard old ghosts and create the ghosts within `cutoff` of every face of the owned region.
  void build(Particles& p, double cutoff);
  /// Refresh ghost positions and velocities (and angular velocities) from their sources: every ghost
  /// after build(), only the ghosts kept by restrict_forward() after it.
  void forward(Particles& p);
  /// `flag` (one per owned particle and ghost, n_total): 1 for the particles some neighbour list refers to.
  /// Flags the source of every flagged ghost too (through earlier ghosts and across ranks, the swaps in
  /// reverse), so that on return an owned particle is flagged when a list on any rank refers to it or to
  /// one of its images; from then on forward() refreshes only the flagged ghosts (the others are read by
  /// no list until the next build: ghosts of particles without neighbours). Collective.
  void restrict_forward(std::vector<char>& flag);
  /// Move owned particles whose (wrapped) y lies outside this slab to the owning rank, with their
  /// contact records. Ghosts are dropped. A particle bound further than a neighbouring slab (a thin slab
  /// crossed between rebuilds) travels hop by hop, one slab per pass the shorter way round the periodic
  /// ring, until no rank holds another's particle (one reduction per pass). Collective.
  void migrate(Particles& p, ContactStore& store);
  /// Number of ghosts of the last build.
  std::size_t ghosts() const { return ghosts_; }

 private:
  struct Swap {
    int dim = 0;
    int peer_send = 0, peer_recv = 0;  // ranks; == own rank for a local periodic image
    bool local = true;
    std::array<double, 3> shift{};     // added to the position of every sent particle
    std::vector<std::int32_t> send;    // local indices of the sources
    std::size_t recv_first = 0, recv_count = 0;
    // after restrict_forward: the k (into send / the received ghosts) forward() still refreshes
    std::vector<std::int32_t> live_send, live_recv;
  };
  void pack(const Particles& p, const Swap& s, std::vector<double>& buf) const;
  void pack_live(const Particles& p, const Swap& s, std::vector<double>& buf) const;
  /// One pass of migrate: every particle not owned here moves one slab toward its owner.
  void migrate_hop(Particles& p, ContactStore& store);
  const SlabDecomposition& slabs_;
  std::vector<Swap> swaps_;
  std::vector<double> send_buf_, recv_buf_;
  std::size_t ghosts_ = 0;
  bool restricted_ = false;
};

}  // namespace cgd::dem
