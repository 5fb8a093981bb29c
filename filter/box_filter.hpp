#pragma once
// Exact box filter of piecewise-constant periodic cell fields, at any point and any width, in a cost
// that does not depend on the width: summed-volume tables (Crow 1984, "Summed-area tables for
// texture mapping", SIGGRAPH; the 3-D form of the integral image).
//
// A cell field f is constant in each cell. Its cumulative integral in cell units,
//   C(s) = integral over [0, s_x] x [0, s_y] x [0, s_z] of f,
// is known exactly at the lattice points (the table T[i][j][k] = sum of f over the cells below), and
// between them it is multilinear in s, because along each axis the integral of a piecewise-constant
// function is piecewise linear:  G(i + a) = (1 - a) G(i) + a G(i + 1).  The integral of f over the box
// [lo, hi] (cell units, any real bounds) is the 8-corner difference of C, i.e. per axis the 4-point
// operator  G(hi) - G(lo)  applied in x, y and z: 64 table reads per field, whatever the width, and
// partial cells count exactly by their overlap. The derivative of the box integral with respect to the
// box centre along an axis replaces that axis's operator by G'(hi) - G'(lo), G'(i + a) = G(i+1) - G(i):
// the difference of the two face integrals, i.e. the exact gradient of the filtered field.
//
// Periodicity: the table is built over the periodic extension of the grid, n + e cells per axis with
// e >= the widest box in cells + 2, and a box's lower corner is wrapped into [0, n); so a box that
// crosses the boundary sees the same cells as its periodic image. Each field's mean is removed before
// summation (and added back analytically) so that the table's values stay O(sqrt(cells)) and the
// 4-point differences keep their precision (round-off ~1e-16 x table magnitude, not x cell count).
#include <array>
#include <cstddef>
#include <vector>

#include "core/periodic_grid.hpp"

namespace cgd::filter {

/// One axis of the box operator: table indices first, first + 1 (lower corner, weights -(1-a), -a)
/// and second, second + 1 (upper corner, weights (1-b), b); for the derivative the weights are
/// (+1, -1) and (-1, +1).
struct AxisOperator {
  int lo = 0, hi = 0;
  std::array<double, 4> value{};  // weights at lo, lo + 1, hi, hi + 1
  std::array<double, 4> slope{};  // d/ds of the integral: weights at lo, lo + 1, hi, hi + 1
};

/// Summed-volume table of K interleaved cell fields on a periodic grid.
template <int K>
class SummedVolumeTable {
 public:
  /// `fields`: K values per cell, cells in file order (x fastest); `max_width_cells`: the widest box
  /// (in cells along each axis) that will be asked for.
  SummedVolumeTable(const PeriodicGrid& grid, const double* fields, std::array<double, 3> max_width_cells);

  /// Mean of each field over the grid.
  const std::array<double, K>& mean() const { return mean_; }
  /// The K values at table point (i, j, k) (the cumulative integral minus the means' part): a box
  /// integral is the sum over the 4 x 4 x 4 points of an AxisOperator's indices of the weights' product
  /// times these values, plus mean x box volume (PeriodicBoxFilter::at).
  const double* point(int i, int j, int k) const { return &table_[at(i, j, k)]; }
  std::size_t bytes() const { return table_.size() * sizeof(double); }

 private:
  std::array<int, 3> n_{}, m_{};     // periodic cells, table points per axis (n + e + 1)
  std::array<double, K> mean_{};
  std::vector<double> table_;        // (m_z, m_y, m_x, K), x fastest
  std::size_t at(int i, int j, int k) const {
    return ((static_cast<std::size_t>(k) * static_cast<std::size_t>(m_[1]) + static_cast<std::size_t>(j)) *
                static_cast<std::size_t>(m_[0]) + static_cast<std::size_t>(i)) * K;
  }
};

/// The box operator of one axis for a box of `width_cells` centred at the wrapped coordinate `s`
/// (cell units, 0 <= s < n).
AxisOperator axis_operator(double s, double width_cells, int n);

/// The filtered quantities at one point (docs/models.md "Filtering", the paper's eqs. 4-5).
struct FilteredPoint {
  double void_fraction = 0;            // filter(eps)
  std::array<double, 3> velocity{};    // Favre: filter(eps u) / filter(eps), m/s
  std::array<double, 3> grad_p{};      // gradient of filter(p), Pa/m
  double pressure = 0;                 // filter(p), Pa (the box average of the pressure)
};

/// The periodic box filter of a snapshot's fluid fields (eps, eps u, p), for boxes of edge up to
/// `max_width_m` (a cube of edge Delta in every direction).
class PeriodicBoxFilter {
 public:
  PeriodicBoxFilter(const PeriodicGrid& grid, const std::vector<double>& void_fraction,
                    const std::vector<double>& eps_velocity, const std::vector<double>& pressure, double max_width_m);
  /// The box of edge `width_m` centred at `position_m` (any position: it is wrapped).
  FilteredPoint at(const double* position_m, double width_m) const;
  /// A box of edges `widths_m` (x, y, z; each at most the constructor's max_width_m) centred at
  /// `position_m`: e.g. a coarse grid's cell (the filter's coarse-grid operator restricts the fields
  /// onto coarse cells with it; docs/filter.md).
  FilteredPoint at(const double* position_m, const std::array<double, 3>& widths_m) const;
  /// The whole-box average: <eps>, <eps u>/<eps>, zero gradient.
  FilteredPoint domain_average() const;
  std::size_t bytes() const { return table_.bytes(); }

 private:
  PeriodicGrid grid_;
  // eps, eps u_x, eps u_y, eps u_z, p interleaved: one pass over the 64 table points gives the five box
  // integrals and the three slopes of the pressure's (40 contiguous bytes per point: few cache misses)
  SummedVolumeTable<5> table_;
};

}  // namespace cgd::filter
