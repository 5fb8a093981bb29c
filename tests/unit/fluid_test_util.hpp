#pragma once
// Shared helpers for the fluid tests (tests/unit/test_fluid.cpp, tests/mpi/test_fluid_mpi.cpp): fill a field
// with an analytic function at the points where the staggered grid stores it (sim/fluid/grid.hpp).
#include <vector>

#include "sim/fluid/grid.hpp"

namespace cgd::fluid::test {

/// fn(x, y, z) at the centres of the owned cells (pressure, eps).
template <class Fn>
void fill_cells(const FluidGrid& g, std::vector<double>& f, Fn&& fn) {
  const auto& h = g.spacing();
  for (int j = 0; j < g.ny_local(); ++j)
    for (int k = 0; k < g.nz(); ++k)
      for (int i = 0; i < g.nx(); ++i)
        f[g.index(i, j, k)] = fn((i + 0.5) * h[0], (g.j0() + j + 0.5) * h[1], (k + 0.5) * h[2]);
}

/// fn(x, y, z) at the lower d-faces of the owned cells (velocity component d).
template <class Fn>
void fill_faces(const FluidGrid& g, int d, std::vector<double>& f, Fn&& fn) {
  const auto& h = g.spacing();
  for (int j = 0; j < g.ny_local(); ++j)
    for (int k = 0; k < g.nz(); ++k)
      for (int i = 0; i < g.nx(); ++i)
        f[g.index(i, j, k)] =
            fn((i + (d == 0 ? 0.0 : 0.5)) * h[0], (g.j0() + j + (d == 1 ? 0.0 : 0.5)) * h[1],
               (k + (d == 2 ? 0.0 : 0.5)) * h[2]);
}

}  // namespace cgd::fluid::test
