#include "sim/dem/neighbor.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#if defined(__AVX2__)
#include <immintrin.h>
#endif

namespace cgd::dem {

namespace {

struct Grid {
  std::array<double, 3> lo{}, inv{};
  std::array<int, 3> n{};
  int cell(const double* x) const {
    int c[3];
    for (int d = 0; d < 3; ++d) c[d] = std::clamp(static_cast<int>((x[d] - lo[d]) * inv[d]), 0, n[d] - 1);
    return (c[2] * n[1] + c[1]) * n[0] + c[0];
  }
  std::size_t count() const { return static_cast<std::size_t>(n[0]) * n[1] * n[2]; }
};

Grid make_grid(const Particles& p, std::size_t count, double cell_size) {
  Grid g;
  std::array<double, 3> hi{};
  for (int d = 0; d < 3; ++d) {
    g.lo[d] = std::numeric_limits<double>::max();
    hi[d] = std::numeric_limits<double>::lowest();
  }
  for (std::size_t i = 0; i < count; ++i)
    for (int d = 0; d < 3; ++d) {
      g.lo[d] = std::min(g.lo[d], p.x[3 * i + d]);
      hi[d] = std::max(hi[d], p.x[3 * i + d]);
    }
  for (int d = 0; d < 3; ++d) {
    if (count == 0) g.lo[d] = hi[d] = 0.0;
    const double extent = hi[d] - g.lo[d];
    g.n[d] = std::max(1, static_cast<int>(std::floor(extent / cell_size)));
    // Keep the cell count bounded (a pathological spread would otherwise allocate without limit).
    g.n[d] = std::min(g.n[d], 4096);
    g.inv[d] = extent > 0 ? g.n[d] / extent : 0.0;
  }
  return g;
}

#if defined(__AVX2__)
/// The candidate scan's compress-store (issue 25, fourth round): for each 4-bit mask of hits, the byte shuffle
/// that moves the hit lanes' 32-bit partner indices to the front, in order (AVX2 has no compress instruction).
constexpr std::array<std::array<std::uint8_t, 16>, 16> make_compress_table() {
  std::array<std::array<std::uint8_t, 16>, 16> t{};
  for (int mask = 0; mask < 16; ++mask) {
    int out = 0;
    for (int lane = 0; lane < 4; ++lane)
      if (mask & (1 << lane)) {
        for (int b = 0; b < 4; ++b) t[mask][4 * out + b] = static_cast<std::uint8_t>(4 * lane + b);
        ++out;
      }
    for (; out < 4; ++out)
      for (int b = 0; b < 4; ++b) t[mask][4 * out + b] = 0x80;  // zero the unused lanes
  }
  return t;
}
alignas(16) constexpr auto kCompress = make_compress_table();
#endif

}  // namespace

void NeighborList::build(const Particles& p, double cell_size, double contact_distance, const float* half_skin,
                         bool with_history) {
  const Grid g = make_grid(p, p.n_total, cell_size);
  const std::size_t ncell = g.count();
  // counting sort of all particles (owned + ghosts) into cells, in place (issue 17: no copy of the cell
  // array, no allocation once the buffers have grown): counts at c + 1, prefix sums make cell_start_[c + 1]
  // the end of cell c, placing the particles from the last down moves it to cell c's start; the last slot
  // holds the particle count. Cell c is then [cell_start_[c + 1], cell_start_[c + 2]), in increasing order.
  cell_start_.assign(ncell + 2, 0);
  cell_of_.resize(p.n_total);
  for (std::size_t i = 0; i < p.n_total; ++i) {
    cell_of_[i] = g.cell(&p.x[3 * i]);
    ++cell_start_[cell_of_[i] + 1];
  }
  for (std::size_t c = 1; c < ncell; ++c) cell_start_[c + 1] += cell_start_[c];
  // the positions too, in cell order (issue 17, third round): the candidate scan below then reads them as
  // streams per row of cells instead of one cache miss per candidate (the scan was 29 % of a developed
  // Table 1 step, most of it on the candidate's position). One array per coordinate (issue 25, fourth round),
  // so that the scan tests four candidates per instruction; each array has kScanPad more slots (zero, never
  // listed) so that the scan's last group of four may read past the last particle.
  const std::size_t slots = p.n_total + kScanPad;
  for (auto* a : {&cell_px_, &cell_py_, &cell_pz_}) a->resize(slots);
  cell_h_.resize(slots);
  cell_items_.resize(slots);
  for (std::size_t k = p.n_total; k < slots; ++k) {
    cell_px_[k] = cell_py_[k] = cell_pz_[k] = 0.0;
    cell_h_[k] = 0.0f;
    cell_items_[k] = -1;
  }
  for (std::size_t i = p.n_total; i-- > 0;) {
    const std::int32_t k = --cell_start_[cell_of_[i] + 1];
    cell_items_[k] = static_cast<std::int32_t>(i);
    cell_px_[k] = p.x[3 * i];
    cell_py_[k] = p.x[3 * i + 1];
    cell_pz_[k] = p.x[3 * i + 2];
    cell_h_[k] = half_skin[i];
  }
  cell_start_[ncell + 1] = static_cast<std::int32_t>(p.n_total);
  const std::int32_t* start = cell_start_.data() + 1;  // start[c] .. start[c + 1]: cell c
  offset.resize(p.n_owned + 1);
  offset[0] = 0;
  // the list is written through a raw pointer, branch-free (issue 17, third round): every candidate is
  // stored and the end advances only for a hit, so the ~15 % hits cost no mispredicted branch; `index` is
  // grown ahead of each particle to hold all its candidates, and cut to the entries at the end
  std::size_t n = 0;
  for (std::size_t i = 0; i < p.n_owned; ++i) {
    const double* xi_ = &p.x[3 * i];
    const double reach_i = contact_distance + static_cast<double>(half_skin[i]);
    const int c = cell_of_[i];
    const int cx = c % g.n[0], cy = (c / g.n[0]) % g.n[1], cz = c / (g.n[0] * g.n[1]);
    const int x0 = std::max(cx - 1, 0), x1 = std::min(cx + 1, g.n[0] - 1);
    // The three cells of a row along x are contiguous in the cell order, so each of the 9 (y, z)
    // rows is one range of cell_items_.
    std::int32_t rb[9], re[9];
    int rows = 0;
    std::size_t candidates = 0;
    for (int z = std::max(cz - 1, 0); z <= std::min(cz + 1, g.n[2] - 1); ++z)
      for (int y = std::max(cy - 1, 0); y <= std::min(cy + 1, g.n[1] - 1); ++y) {
        const int row = (z * g.n[1] + y) * g.n[0];
        rb[rows] = start[row + x0];
        re[rows] = start[row + x1 + 1];
        candidates += static_cast<std::size_t>(re[rows] - rb[rows]);
        ++rows;
      }
    // room for every candidate, and for the last group of four the vector scan stores whole
    if (n + candidates + kScanPad > index.size()) index.resize(std::max(2 * index.size(), n + candidates + 4096));
    std::int32_t* out = index.data();
    const std::size_t first = n;
    const auto self = static_cast<std::int32_t>(i);
    const double *px = cell_px_.data(), *py = cell_py_.data(), *pz = cell_pz_.data();
    const float* ph = cell_h_.data();
    const std::int32_t* items = cell_items_.data();
#if defined(__AVX2__)
    // four candidates at a time, the same operations in the same order as the scalar test below, so the
    // same pairs are listed bit for bit: r2 = (dx dx + dy dy) + dz dz (no FMA: -ffp-contract=off) against
    // (reach_i + h_j)^2; the hits' partner indices are compressed to the front and stored as four (the
    // lanes after the hits are overwritten by the next group or cut by the final resize)
    const __m256d vx = _mm256_set1_pd(xi_[0]), vy = _mm256_set1_pd(xi_[1]), vz = _mm256_set1_pd(xi_[2]);
    const __m256d vreach = _mm256_set1_pd(reach_i);
    const __m128i vself = _mm_set1_epi32(self);
    for (int r = 0; r < rows; ++r) {
      for (std::int32_t k = rb[r]; k < re[r]; k += 4) {
        const __m256d ddx = _mm256_sub_pd(vx, _mm256_loadu_pd(px + k));
        const __m256d ddy = _mm256_sub_pd(vy, _mm256_loadu_pd(py + k));
        const __m256d ddz = _mm256_sub_pd(vz, _mm256_loadu_pd(pz + k));
        const __m256d r2 =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(ddx, ddx), _mm256_mul_pd(ddy, ddy)), _mm256_mul_pd(ddz, ddz));
        const __m256d cut = _mm256_add_pd(vreach, _mm256_cvtps_pd(_mm_loadu_ps(ph + k)));
        const __m128i j4 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(items + k));
        unsigned hit = static_cast<unsigned>(_mm256_movemask_pd(_mm256_cmp_pd(r2, _mm256_mul_pd(cut, cut), _CMP_LT_OQ)));
        hit &= ~static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(j4, vself))));
        const std::int32_t left = re[r] - k;
        if (left < 4) hit &= (1u << left) - 1u;
        const __m128i packed =
            _mm_shuffle_epi8(j4, _mm_load_si128(reinterpret_cast<const __m128i*>(kCompress[hit].data())));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + n), packed);
        n += static_cast<std::size_t>(std::popcount(hit));
      }
    }
#else
    for (int r = 0; r < rows; ++r) {
      for (std::int32_t k = rb[r]; k < re[r]; ++k) {
        const double ddx = xi_[0] - px[k], ddy = xi_[1] - py[k], ddz = xi_[2] - pz[k];
        const double cut = reach_i + static_cast<double>(ph[k]);
        const std::int32_t j = items[k];
        out[n] = j;
        n += static_cast<std::size_t>((ddx * ddx + ddy * ddy + ddz * ddz < cut * cut) & (j != self));
      }
    }
#endif
    // canonical order: by partner id (see header); lists are short, insertion sort
    for (std::size_t a = first + 1; a < n; ++a) {
      const std::int32_t j = out[a];
      const std::int64_t key = p.id[j];
      std::size_t b = a;
      while (b > first && p.id[out[b - 1]] > key) {
        out[b] = out[b - 1];
        --b;
      }
      out[b] = j;
    }
    offset[i + 1] = static_cast<std::int64_t>(n);
  }
  index.resize(n);
  if (with_history) xi.assign(3 * index.size(), 0.0);
  else xi.clear();
}

void NeighborList::save_history(const Particles& p, ContactStore& store) const {
  store.clear();
  store.offset.reserve(p.n_owned + 1);
  for (std::size_t i = 0; i < p.n_owned; ++i) {
    if (!xi.empty()) {
      for (std::int64_t k = offset[i]; k < offset[i + 1]; ++k) {
        const double* s = &xi[3 * k];
        if (s[0] != 0.0 || s[1] != 0.0 || s[2] != 0.0) {
          store.partner.push_back(p.id[partner(static_cast<std::size_t>(k))]);
          store.xi.insert(store.xi.end(), s, s + 3);
        }
      }
    }
    store.offset.push_back(static_cast<std::int64_t>(store.partner.size()));
  }
}

void NeighborList::load_history(const Particles& p, const ContactStore& store) {
  if (xi.empty() || store.offset.size() != p.n_owned + 1) return;
  for (std::size_t i = 0; i < p.n_owned; ++i) {
    for (std::int64_t s = store.offset[i]; s < store.offset[i + 1]; ++s) {
      // neighbours are sorted by id: binary search the partner
      const auto begin = index.begin() + offset[i], end = index.begin() + offset[i + 1];
      const auto it = std::lower_bound(begin, end, store.partner[s], [&](std::int32_t j, std::int64_t id) {
        return p.id[j & kPartnerMask] < id;
      });
      // A stored contact is always within the cutoff, so it is found; if not (it cannot touch
      // before the next rebuild either) the record is dropped.
      if (it != end && p.id[*it & kPartnerMask] == store.partner[s]) {
        const std::size_t k = static_cast<std::size_t>(it - index.begin());
        xi[3 * k] = store.xi[3 * s];
        xi[3 * k + 1] = store.xi[3 * s + 1];
        xi[3 * k + 2] = store.xi[3 * s + 2];
        index[k] = with_spring_flag(index[k]);  // may be non-zero
      }
    }
  }
}

std::size_t NeighborList::bytes() const {
  return offset.capacity() * sizeof(std::int64_t) + index.capacity() * sizeof(std::int32_t) +
         xi.capacity() * sizeof(double) +
         (cell_start_.capacity() + cell_items_.capacity() + cell_of_.capacity()) * sizeof(std::int32_t) +
         (cell_px_.capacity() + cell_py_.capacity() + cell_pz_.capacity()) * sizeof(double) +
         cell_h_.capacity() * sizeof(float);
}

std::vector<std::int32_t> spatial_order(const Particles& p, double cell_size) {
  const Grid g = make_grid(p, p.n_owned, cell_size);
  std::vector<std::int32_t> start(g.count() + 1, 0), cell(p.n_owned);
  for (std::size_t i = 0; i < p.n_owned; ++i) {
    cell[i] = g.cell(&p.x[3 * i]);
    ++start[cell[i] + 1];
  }
  for (std::size_t c = 0; c + 1 < start.size(); ++c) start[c + 1] += start[c];
  std::vector<std::int32_t> order(p.n_owned);
  for (std::size_t i = 0; i < p.n_owned; ++i) order[start[cell[i]]++] = static_cast<std::int32_t>(i);
  return order;
}

}  // namespace cgd::dem
