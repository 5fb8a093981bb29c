#pragma once
// The TSC particle <-> grid operator on a whole periodic grid (core/periodic_grid.hpp), one process:
// the same kernel (core/tsc_kernel.hpp) and the same 27-cell loop as the coupling's slab version
// (sim/coupling/exchange.hpp for_each_tsc_cell), for code that holds the whole grid — the filter's
// coarse-grid operator (docs/filter.md "The coarse grid's operator"), which applies a-priori what a
// coarse run applies: deposit the particles' volume with the TSC weights, a void fraction with the
// coupler's conservative floor, and interpolate cell fields back to the particles with the same
// weights (sim/coupling/coupler.cpp compute_drag, interpolate_fluid).
//
// Kernel (Hockney & Eastwood 1988, ch. 5): per axis the quadratic B-spline of width 3 cells,
// w_-1 = (1/2 - d)^2/2, w_0 = 3/4 - d^2, w_+1 = (1/2 + d)^2/2, d the particle's offset from its
// nearest cell centre; the 27 weights are the products and sum to 1 (deposits conserve volume).
// Cell (i, j, k) is centred at origin + (i + 1/2, j + 1/2, k + 1/2) h, as in the engine.
//
// Transfer function (the known answer of the unit test TscGrid.*): for a continuous density
// rho(x) = cos(k x) along one axis, the deposit on cell c is cos(k x_c) W^(k) with
// W^(k) = [sin(k h/2)/(k h/2)]^3 (the B-spline is the 3-fold convolution of the one-cell box), and the
// interpolation at a cell centre x_c gives sum_m w(m h) cos(k (x_c + m h)) = cos(k x_c) (3/4 + cos(k h)/4).
// So deposit + interpolation, evaluated at cell centres, multiplies the mode by
//     T(k) = [sin(k h/2)/(k h/2)]^3 (3/4 + cos(k h)/4)  per axis,   T ~ 1 - (k h)^2/4 = 1 - k^2 s^2/2,
// s^2 = h^2/2 the variance of the combined operator (1/4 h^2 from each B-spline): that of a box of
// width sqrt(6) h = 2.45 h (a box of width W has variance W^2/12).
#include <algorithm>
#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/periodic_grid.hpp"
#include "core/tsc_kernel.hpp"

namespace cgd {

/// The 27 cells and TSC weights of a point x (m, any position: wrapped periodically) on the whole
/// periodic grid g. Calls f(cell index in file order, weight) for each, z slowest, x fastest (the
/// coupler's order); the weights sum to 1. A grid of 1 or 2 cells along an axis adds weights of
/// different offsets into the same cell (the periodic images), as a periodic deposit must.
template <class F>
inline void for_each_tsc_cell(const PeriodicGrid& g, const double* x, F&& f) {
  AxisWeights a[3];
  int idx[3][3];
  for (int d = 0; d < 3; ++d) {
    a[d] = tsc_weights(x[d], g.origin_m[d], g.spacing_m[d]);
    const int n = g.cells[d];
    for (int m = 0; m < 3; ++m) idx[d][m] = ((a[d].first + m) % n + n) % n;
  }
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < 3; ++b) {
      const double wyz = a[1].w[b] * a[2].w[c];
      const std::size_t row = g.index(0, idx[1][b], idx[2][c]);
      for (int m = 0; m < 3; ++m) f(row + static_cast<std::size_t>(idx[0][m]), a[0].w[m] * wyz);
    }
}

/// Solids fraction of the cells: sum over particles of volume_i w_ic / V_cell (positions count x 3,
/// m; volumes per particle, m^3, or one value for all when volumes.size() == 1).
inline std::vector<double> tsc_deposit_solids_fraction(const PeriodicGrid& g, const std::vector<double>& positions,
                                                       const std::vector<double>& volumes) {
  std::vector<double> phi(g.cell_count(), 0.0);
  const std::size_t n = positions.size() / 3;
  const double inv_cell = 1.0 / g.cell_volume_m3();
  for (std::size_t i = 0; i < n; ++i) {
    const double vol = (volumes.size() == 1 ? volumes[0] : volumes[i]) * inv_cell;
    for_each_tsc_cell(g, &positions[3 * i], [&](std::size_t c, double w) { phi[c] += vol * w; });
  }
  return phi;
}

/// The coupler's conservative void-fraction floor (sim/coupling/coupler.cpp compute_drag), on a whole
/// grid: cells with eps = 1 - phi below `floor` are raised to it, and the excess is taken back from
/// the other cells in proportion to their room eps - floor, so sum eps is unchanged. Returns the
/// number of floored cells; phi is replaced by 1 - eps. RunError when the room is too small (as the
/// coupler). The same arithmetic as the coupler's, cell by cell.
inline long long apply_void_fraction_floor(std::vector<double>& phi, double floor) {
  double excess = 0, room = 0;
  long long floored = 0;
  for (double p : phi) {
    const double eps = 1.0 - p;
    if (eps < floor) {
      excess += floor - eps;
      ++floored;
    } else {
      room += eps - floor;
    }
  }
  if (excess > 0 && !(room > excess))
    throw RunError("solids fraction too high to keep the void fraction above its floor " + std::to_string(floor) +
                   " anywhere");
  const double take_back = excess > 0 ? excess / room : 0.0;
  for (double& p : phi) {
    double eps = 1.0 - p;
    if (eps < floor) eps = floor;
    else eps -= take_back * (eps - floor);
    p = 1.0 - eps;
  }
  return floored;
}

/// TSC interpolation of K interleaved cell fields (K values per cell, file order) at x: out[q] =
/// sum_c w_c field[K c + q].
template <int K>
inline std::array<double, K> tsc_interpolate(const PeriodicGrid& g, const double* fields, const double* x) {
  std::array<double, K> out{};
  for_each_tsc_cell(g, x, [&](std::size_t c, double w) {
    for (int q = 0; q < K; ++q) out[q] += w * fields[K * c + q];
  });
  return out;
}

/// Cell-centred pressure gradient by central differences on the periodic grid, as the coupler forms it
/// (Coupler::interpolate_fluid): (p_{i+1} - p_{i-1}) / (2 h) per axis. Returns cells x 3.
inline std::vector<double> central_pressure_gradient(const PeriodicGrid& g, const std::vector<double>& p) {
  std::vector<double> out(3 * g.cell_count());
  const int nx = g.cells[0], ny = g.cells[1], nz = g.cells[2];
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const std::size_t c = g.index(i, j, k);
        out[3 * c + 0] = (p[g.index((i + 1) % nx, j, k)] - p[g.index((i + nx - 1) % nx, j, k)]) / (2.0 * g.spacing_m[0]);
        out[3 * c + 1] = (p[g.index(i, (j + 1) % ny, k)] - p[g.index(i, (j + ny - 1) % ny, k)]) / (2.0 * g.spacing_m[1]);
        out[3 * c + 2] = (p[g.index(i, j, (k + 1) % nz)] - p[g.index(i, j, (k + nz - 1) % nz)]) / (2.0 * g.spacing_m[2]);
      }
  return out;
}

}  // namespace cgd
