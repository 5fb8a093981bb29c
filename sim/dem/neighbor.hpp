#pragma once
// Neighbour search: cell binning + Verlet list with a skin per particle (issue 25): particles i and j are
// listed when r_ij < d + h_i + h_j, h_i particle i's half-skin (DemSystem sets it from the particle's own
// speed, so that the slow particles of a dense suspension do not carry the fastest one's skin; a fixed skin
// is h_i = skin / 2 for all). The list holds every pair that can touch while no particle has moved more than
// its own h_i since the build (|dr| <= |dx_i| + |dx_j| <= h_i + h_j).
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
  /// Build the list of owned particles from positions of owned + ghost particles: the pairs closer than
  /// contact_distance + half_skin[i] + half_skin[j] (half_skin: one per owned particle and ghost, each at most
  /// (cell_size - contact_distance) / 2; cell_size is the binning's). `with_history`: keep one tangential
  /// spring (3 doubles) per entry.
  void build(const Particles& p, double cell_size, double contact_distance, const float* half_skin,
             bool with_history);
  /// Active contacts (non-zero spring) of every owned particle, keyed by partner id.
  void save_history(const Particles& p, ContactStore& store) const;
  /// Set each entry's spring from the store (entries whose partner is not in the store get zero).
  void load_history(const Particles& p, const ContactStore& store);

  std::size_t entries() const { return index.size(); }
  std::size_t bytes() const;

  /// The top bit of an `index` entry (issue 25, third round) says that the entry's spring may be non-zero;
  /// clear, the spring is +0.0 in all three components. The force pass then reads an entry's spring only
  /// where its pair touches or the flag is set (a contact that just ended), not the 24 bytes of every entry
  /// (3.4 entries per particle in a dense state, 95 % of them never touching). Set by the force pass where a
  /// pair touches and by load_history, cleared where the force pass zeroes an ended contact's spring; a build
  /// clears every flag. The partner's local index is `index[e] & kPartnerMask` (`partner(e)`).
  static constexpr std::int32_t kPartnerMask = 0x7fffffff;
  static constexpr std::uint32_t kSpringFlag = 0x80000000u;
  std::int32_t partner(std::size_t e) const { return index[e] & kPartnerMask; }
  static bool spring_flagged(std::int32_t raw) { return raw < 0; }
  static std::int32_t with_spring_flag(std::int32_t raw) {
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(raw) | kSpringFlag);
  }

  std::vector<std::int64_t> offset;  // n_owned + 1
  std::vector<std::int32_t> index;   // local index of the neighbour (& kPartnerMask; top bit: kSpringFlag)
  std::vector<double> xi;            // tangential spring per entry (3 doubles), as seen from i

 private:
  std::vector<std::int32_t> cell_start_, cell_items_, cell_of_;
  // positions and half-skins in cell order (cell_items_'s), rebuilt each build, kScanPad slots more
  static constexpr std::size_t kScanPad = 4;
  std::vector<double> cell_px_, cell_py_, cell_pz_;
  std::vector<float> cell_h_;
};

/// Permutation that orders the owned particles by the cell they lie in (memory locality).
std::vector<std::int32_t> spatial_order(const Particles& p, double cell_size);

}  // namespace cgd::dem
