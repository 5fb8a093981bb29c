#pragma once
// Neighbour search: cell binning + Verlet list with a skin (cutoff = contact distance + skin).
// The list is *full* (each owned particle lists all its neighbours, owned or ghost) and each
// particle's neighbours are sorted by global id. With the newton-off evaluation this makes every
// particle's force a sum in a canonical order: the result does not depend on the particle order,
// on when the list was rebuilt, on the number of ranks, or on a restart -- trajectories agree bit
// for bit across all of these. Tangential history lives beside the list entries and is carried
// across rebuilds by the ContactStore (keyed by partner id).
#include <cstdint>
#include <vector>

#include "sim/dem/particles.hpp"

namespace cgd::dem {

class NeighborList {
 public:
  /// Build the list of owned particles from positions of owned + ghost particles.
  /// `with_history`: keep one tangential spring (3 doubles) per entry.
  void build(const Particles& p, double cutoff, bool with_history);
  /// Active contacts (non-zero spring) of every owned particle, keyed by partner id.
  void save_history(const Particles& p, ContactStore& store) const;
  /// Set each entry's spring from the store (entries whose partner is not in the store get zero).
  void load_history(const Particles& p, const ContactStore& store);

  std::size_t entries() const { return index.size(); }
  std::size_t bytes() const;

  std::vector<std::int64_t> offset;  // n_owned + 1
  std::vector<std::int32_t> index;   // local index of the neighbour
  std::vector<double> xi;            // tangential spring per entry (3 doubles), as seen from i

 private:
  std::vector<std::int32_t> cell_start_, cell_items_, cell_of_;
  std::vector<double> cell_x_;  // positions in cell order (cell_items_'s), 3 per particle, rebuilt each build
};

/// Permutation that orders the owned particles by the cell they lie in (memory locality).
std::vector<std::int32_t> spatial_order(const Particles& p, double cell_size);

}  // namespace cgd::dem
