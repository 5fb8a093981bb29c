#pragma once
// Particle <-> grid exchange on a coupling grid replicated on every rank (issue 25): the whole y range,
// j0 = 0 and ny_local = n_y, with `ghost` planes below and above (periodic copies), fields stored with y
// slowest, index (j + ghost) * n_z n_x + k n_x + i, x and z periodic by index. Every rank's particles may
// lie anywhere in y (their DEM slabs are chosen for balance, not to match the fluid's FFTW rows), so each
// rank deposits into a whole grid; `fold_ghost_rows` adds the ghost planes into the rows they wrap to and
// `reduce_rows_to_owners` sums the rows over the ranks onto the fluid rows each rank owns (the transpose of
// the gather below), so the total deposited equals the sum over particles to round-off, on any number of
// ranks. The other way, each rank computes the cell fields the particles read on its own fluid rows and
// `gather_rows` gives every rank every row and refills the periodic ghost planes. The fluid grid's index of
// an owned cell plus j0 * plane is its index here (both layouts put `ghost` planes first). One rank: no MPI,
// the fold and ghost copies alone, the arithmetic of the slab exchange this replaced.
#include <mpi.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstddef>
#include <initializer_list>
#include <vector>

#include "core/tsc_kernel.hpp"

namespace cgd::coupling {

struct GridView {
  std::array<int, 3> cells{};      // global (n_x, n_y, n_z)
  std::array<double, 3> spacing{};  // m
  int j0 = 0, ny_local = 0, ghost = 2;
  std::size_t plane() const { return static_cast<std::size_t>(cells[0]) * cells[2]; }
  std::size_t storage_size() const { return plane() * static_cast<std::size_t>(ny_local + 2 * ghost); }
  std::size_t index(int i, int j_local, int k) const {
    return static_cast<std::size_t>(j_local + ghost) * plane() + static_cast<std::size_t>(k) * cells[0] + i;
  }
  double cell_volume() const { return spacing[0] * spacing[1] * spacing[2]; }
};

/// The 27 cells and weights of a particle at x (m; x and z may lie outside the box, y within a
/// cell of the view's rows). Calls f(storage index, weight) for each; the weights sum to 1.
template <class F>
inline void for_each_tsc_cell(const GridView& g, const double* x, F&& f) {
  const AxisWeights ax = tsc_weights(x[0], 0.0, g.spacing[0]);
  const AxisWeights ay = tsc_weights(x[1], g.j0 * g.spacing[1], g.spacing[1]);
  const AxisWeights az = tsc_weights(x[2], 0.0, g.spacing[2]);
  int ix[3], iz[3];
  for (int a = 0; a < 3; ++a) {
    ix[a] = ((ax.first + a) % g.cells[0] + g.cells[0]) % g.cells[0];
    iz[a] = ((az.first + a) % g.cells[2] + g.cells[2]) % g.cells[2];
  }
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < 3; ++b) {
      const double wyz = ay.w[b] * az.w[c];
      const std::size_t row = g.index(0, ay.first + b, iz[c]);
      for (int a = 0; a < 3; ++a) f(row + static_cast<std::size_t>(ix[a]), ax.w[a] * wyz);
    }
}

/// A particle's TSC stencil on the view (issue 17: computed once per fluid step and kept, instead of
/// the kernel and its integer modulos 5 times per particle and step): the first cell along each axis
/// (x and z unwrapped, y local) and the particle's offset d from the nearest cell centre along each
/// axis, from which the weights follow exactly as tsc_weights computes them.
struct Stencil {
  std::int32_t first[3] = {0, 0, 0};
  double d[3] = {0, 0, 0};
};

/// The stencil of a particle at x (the arithmetic of tsc_weights: s = (x - x0)/h, c = floor(s), d = s - c - 1/2).
inline Stencil make_stencil(const GridView& g, const double* x) {
  Stencil st;
  const double x0[3] = {0.0, g.j0 * g.spacing[1], 0.0};
  for (int a = 0; a < 3; ++a) {
    const double s = (x[a] - x0[a]) / g.spacing[a];
    const double c = std::floor(s);
    st.d[a] = s - c - 0.5;
    st.first[a] = static_cast<int>(c) - 1;
  }
  return st;
}

/// The three weights of one axis from the offset d (tsc_weights' expressions).
inline void stencil_weights(double d, double* w) {
  w[0] = 0.5 * (0.5 - d) * (0.5 - d);
  w[1] = 0.75 - d * d;
  w[2] = 0.5 * (0.5 + d) * (0.5 + d);
}

/// Periodic index in [0, n) (a modulo only off the fast path).
inline int wrap_index(int i, int n) {
  if (static_cast<unsigned>(i) < static_cast<unsigned>(n)) return i;
  return ((i % n) + n) % n;
}

/// A kept stencil's three cells along x and along z, wrapped into the periodic grid.
inline void stencil_columns(const GridView& g, const Stencil& st, int ix[3], int iz[3]) {
  for (int a = 0; a < 3; ++a) {
    ix[a] = wrap_index(st.first[0] + a, g.cells[0]);
    iz[a] = wrap_index(st.first[2] + a, g.cells[2]);
  }
}

/// for_each_tsc_cell from a kept stencil: the same cells, order and weights, bit for bit.
template <class F>
inline void for_each_stencil_cell(const GridView& g, const Stencil& st, F&& f) {
  double wx[3], wy[3], wz[3];
  stencil_weights(st.d[0], wx);
  stencil_weights(st.d[1], wy);
  stencil_weights(st.d[2], wz);
  int ix[3], iz[3];
  stencil_columns(g, st, ix, iz);
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < 3; ++b) {
      const double wyz = wy[b] * wz[c];
      const std::size_t row = g.index(0, st.first[1] + b, iz[c]);
      for (int a = 0; a < 3; ++a) f(row + static_cast<std::size_t>(ix[a]), wx[a] * wyz);
    }
}

/// The gradient of the kernel at the particle, grad w_pc, for the cells of for_each_stencil_cell in the same order:
/// f(storage index, gx, gy, gz). Along each axis dw/dx of stencil_weights' three weights (d = s - c - 1/2,
/// ds/dx = 1/h): -(1/2 - d)/h, -2d/h, (1/2 + d)/h, times the other two axes' weights (the particle-phase pressure,
/// coupler.hpp).
template <class F>
inline void for_each_stencil_cell_gradient(const GridView& g, const Stencil& st, F&& f) {
  double w[3][3], dw[3][3];
  for (int a = 0; a < 3; ++a) {
    stencil_weights(st.d[a], w[a]);
    dw[a][0] = -(0.5 - st.d[a]) / g.spacing[a];
    dw[a][1] = -2.0 * st.d[a] / g.spacing[a];
    dw[a][2] = (0.5 + st.d[a]) / g.spacing[a];
  }
  int ix[3], iz[3];
  stencil_columns(g, st, ix, iz);
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < 3; ++b) {
      const std::size_t row = g.index(0, st.first[1] + b, iz[c]);
      for (int a = 0; a < 3; ++a)
        f(row + static_cast<std::size_t>(ix[a]), dw[0][a] * w[1][b] * w[2][c], w[0][a] * dw[1][b] * w[2][c],
          w[0][a] * w[1][b] * dw[2][c]);
    }
}

/// The fluid rows of every rank: rank r owns global rows [j0[r], j0[r] + count[r]), increasing with r and
/// together [0, n_y) (FFTW-MPI's blocks, sim/fluid/grid.hpp).
struct RowOwners {
  std::vector<int> j0, count;
  /// The rows of every rank of `comm`, from each rank's own (j0, count). Collective.
  static RowOwners gather(MPI_Comm comm, int j0, int count);
};

/// Add the ghost planes of a field of `k` values per cell (interleaved) into the rows they wrap to (lower
/// ghosts onto the top rows, then upper ghosts onto the bottom rows) and zero them. `g` covers the whole y
/// range (j0 = 0, ny_local = n_y). Local.
void fold_ghost_rows(const GridView& g, double* field, int k);

/// Sum rows [0, n_y) of a field of `k` values per cell over the ranks (one MPI_Reduce_scatter) into the rows
/// each rank owns (`rows`); the other rows keep this rank's own values. After fold_ghost_rows. Collective.
void reduce_rows_to_owners(MPI_Comm comm, const GridView& g, const RowOwners& rows, double* field, int k);

/// Give every rank the owners' values of every row (one MPI_Allgatherv; each rank's own rows are the input),
/// then fill the ghost planes periodically (rows -ghost.. -1 from the top, n_y.. from the bottom). Collective.
void gather_rows(MPI_Comm comm, const GridView& g, const RowOwners& rows, double* field, int k);

}  // namespace cgd::coupling
