#include "filter/box_filter.hpp"

#include <cmath>
#include <stdexcept>

namespace cgd::filter {

AxisOperator axis_operator(double s, double width_cells, int n) {
  AxisOperator op;
  double lo = s - 0.5 * width_cells;
  lo -= n * std::floor(lo / n);
  if (lo >= n) lo -= n;  // round-off of a tiny negative lo
  const double hi = lo + width_cells;
  const double flo = std::floor(lo), fhi = std::floor(hi);
  const double a = lo - flo, b = hi - fhi;
  op.lo = static_cast<int>(flo);
  op.hi = static_cast<int>(fhi);
  op.value = {-(1.0 - a), -a, 1.0 - b, b};
  op.slope = {1.0, -1.0, -1.0, 1.0};
  return op;
}

template <int K>
SummedVolumeTable<K>::SummedVolumeTable(const PeriodicGrid& grid, const double* fields,
                                        std::array<double, 3> max_width_cells) {
  for (int a = 0; a < 3; ++a) {
    n_[a] = grid.cells[a];
    if (!(max_width_cells[a] >= 0) || max_width_cells[a] > 1e7)
      throw std::invalid_argument("SummedVolumeTable: bad maximum width");
    m_[a] = n_[a] + static_cast<int>(std::ceil(max_width_cells[a])) + 3;
  }
  const std::size_t cells = grid.cell_count();
  for (std::size_t c = 0; c < cells; ++c)
    for (int q = 0; q < K; ++q) mean_[q] += fields[K * c + q];
  for (int q = 0; q < K; ++q) mean_[q] /= static_cast<double>(cells);

  table_.assign(static_cast<std::size_t>(m_[0]) * m_[1] * m_[2] * K, 0.0);
  // table point (i, j, k) >= 1 receives cell (i-1, j-1, k-1) of the periodic extension ...
  for (int k = 1; k < m_[2]; ++k)
    for (int j = 1; j < m_[1]; ++j)
      for (int i = 1; i < m_[0]; ++i) {
        const std::size_t c = grid.index((i - 1) % n_[0], (j - 1) % n_[1], (k - 1) % n_[2]);
        double* t = &table_[at(i, j, k)];
        for (int q = 0; q < K; ++q) t[q] = fields[K * c + q] - mean_[q];
      }
  // ... and prefix sums along x, then y, then z turn cell values into the cumulative integral.
  for (int k = 1; k < m_[2]; ++k)
    for (int j = 1; j < m_[1]; ++j)
      for (int i = 2; i < m_[0]; ++i)
        for (int q = 0; q < K; ++q) table_[at(i, j, k) + q] += table_[at(i - 1, j, k) + q];
  for (int k = 1; k < m_[2]; ++k)
    for (int j = 2; j < m_[1]; ++j)
      for (int i = 1; i < m_[0]; ++i)
        for (int q = 0; q < K; ++q) table_[at(i, j, k) + q] += table_[at(i, j - 1, k) + q];
  for (int k = 2; k < m_[2]; ++k)
    for (int j = 1; j < m_[1]; ++j)
      for (int i = 1; i < m_[0]; ++i)
        for (int q = 0; q < K; ++q) table_[at(i, j, k) + q] += table_[at(i, j, k - 1) + q];
}

template class SummedVolumeTable<5>;

namespace {
std::vector<double> interleave(const std::vector<double>& eps, const std::vector<double>& eps_u,
                               const std::vector<double>& p) {
  if (eps_u.size() != 3 * eps.size() || p.size() != eps.size())
    throw std::invalid_argument("PeriodicBoxFilter: fields of different sizes");
  std::vector<double> out(5 * eps.size());
  for (std::size_t c = 0; c < eps.size(); ++c) {
    out[5 * c] = eps[c];
    for (int d = 0; d < 3; ++d) out[5 * c + 1 + d] = eps_u[3 * c + d];
    out[5 * c + 4] = p[c];
  }
  return out;
}
std::array<double, 3> width_in_cells(const PeriodicGrid& g, double width_m) {
  return {width_m / g.spacing_m[0], width_m / g.spacing_m[1], width_m / g.spacing_m[2]};
}
}  // namespace

PeriodicBoxFilter::PeriodicBoxFilter(const PeriodicGrid& grid, const std::vector<double>& void_fraction,
                                     const std::vector<double>& eps_velocity, const std::vector<double>& pressure,
                                     double max_width_m)
    : grid_(grid),
      table_(grid, interleave(void_fraction, eps_velocity, pressure).data(), width_in_cells(grid, max_width_m)) {}

FilteredPoint PeriodicBoxFilter::at(const double* position_m, double width_m) const {
  return at(position_m, std::array<double, 3>{width_m, width_m, width_m});
}

FilteredPoint PeriodicBoxFilter::at(const double* position_m, const std::array<double, 3>& widths_m) const {
  std::array<AxisOperator, 3> op;
  for (int a = 0; a < 3; ++a)
    op[a] = axis_operator(grid_.wrapped_cell_coordinate(position_m[a], a), widths_m[a] / grid_.spacing_m[a], grid_.cells[a]);
  const int ix[4] = {op[0].lo, op[0].lo + 1, op[0].hi, op[0].hi + 1};
  const int iy[4] = {op[1].lo, op[1].lo + 1, op[1].hi, op[1].hi + 1};
  const int iz[4] = {op[2].lo, op[2].lo + 1, op[2].hi, op[2].hi + 1};
  const auto &vx = op[0].value, &vy = op[1].value, &vz = op[2].value;
  const auto &sx = op[0].slope, &sy = op[1].slope, &sz = op[2].slope;
  double flow[5] = {0, 0, 0, 0, 0}, slope[3] = {0, 0, 0};
  for (int r = 0; r < 4; ++r)
    for (int q = 0; q < 4; ++q) {
      const double vyz = vy[q] * vz[r], syz = sy[q] * vz[r], ysz = vy[q] * sz[r];
      const double* row = table_.point(0, iy[q], iz[r]);
      for (int p = 0; p < 4; ++p) {
        const double* t = row + 5 * static_cast<std::ptrdiff_t>(ix[p]);
        const double w = vx[p] * vyz;
        flow[0] += w * t[0];
        flow[1] += w * t[1];
        flow[2] += w * t[2];
        flow[3] += w * t[3];
        flow[4] += w * t[4];
        slope[0] += sx[p] * vyz * t[4];
        slope[1] += vx[p] * syz * t[4];
        slope[2] += vx[p] * ysz * t[4];
      }
    }
  // the removed means, integrated over the box exactly: mean x box volume in cells
  const double volume_cells = (op[0].hi - op[0].lo + vx[1] + vx[3]) * (op[1].hi - op[1].lo + vy[1] + vy[3]) *
                              (op[2].hi - op[2].lo + vz[1] + vz[3]);
  const auto& mean = table_.mean();
  for (int c = 0; c < 5; ++c) flow[c] += mean[c] * volume_cells;
  FilteredPoint f;
  f.void_fraction = flow[0] / volume_cells;
  for (int d = 0; d < 3; ++d) f.velocity[d] = flow[1 + d] / flow[0];
  for (int a = 0; a < 3; ++a) f.grad_p[a] = slope[a] / (volume_cells * grid_.spacing_m[a]);
  f.pressure = flow[4] / volume_cells;
  return f;
}

FilteredPoint PeriodicBoxFilter::domain_average() const {
  FilteredPoint f;
  const auto& mean = table_.mean();
  f.void_fraction = mean[0];
  for (int d = 0; d < 3; ++d) f.velocity[d] = mean[1 + d] / mean[0];
  f.pressure = mean[4];
  return f;
}

}  // namespace cgd::filter
