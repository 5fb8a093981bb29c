#pragma once
// The periodic Cartesian grid of the fluid fields, as the engine solves them and the snapshot stores
// them (ARCHITECTURE.md "Files"): n_x x n_y x n_z cells of edge (h_x, h_y, h_z) from `origin`, periodic in
// every direction, cell (i, j, k) spanning [origin + (i, j, k) h, origin + (i+1, j+1, k+1) h).
// Cell arrays are in file order (k, j, i), x fastest. Shared by the engine's output and the filter.
#include <array>
#include <cmath>
#include <cstddef>

namespace cgd {

struct PeriodicGrid {
  std::array<int, 3> cells{};            // (n_x, n_y, n_z)
  std::array<double, 3> spacing_m{};     // (h_x, h_y, h_z)
  std::array<double, 3> origin_m{};

  std::size_t cell_count() const {
    return static_cast<std::size_t>(cells[0]) * static_cast<std::size_t>(cells[1]) * static_cast<std::size_t>(cells[2]);
  }
  /// Index of cell (i, j, k) in file order (x fastest).
  std::size_t index(int i, int j, int k) const {
    return (static_cast<std::size_t>(k) * static_cast<std::size_t>(cells[1]) + static_cast<std::size_t>(j)) *
               static_cast<std::size_t>(cells[0]) +
           static_cast<std::size_t>(i);
  }
  double edge_m(int axis) const { return cells[axis] * spacing_m[axis]; }
  double cell_volume_m3() const { return spacing_m[0] * spacing_m[1] * spacing_m[2]; }
  /// Cube root of the cell volume: "the" cell size of docs/models.md (Delta_fluid).
  double cell_size_m() const { return std::cbrt(cell_volume_m3()); }
  /// Position along `axis` in cell units, wrapped into [0, n): s = (x - origin)/h mod n.
  double wrapped_cell_coordinate(double x_m, int axis) const {
    const double n = cells[axis];
    double s = (x_m - origin_m[axis]) / spacing_m[axis];
    s -= n * std::floor(s / n);
    return s < n ? s : 0.0;  // s == n only by round-off of a tiny negative s
  }
};

}  // namespace cgd
