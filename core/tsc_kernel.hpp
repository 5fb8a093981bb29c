#pragma once
// Particle <-> grid kernel of the coupling (sim/coupling/exchange.hpp), also used by the filter's
// coarse-grid operator, so that a-priori filtering applies exactly what a coarse run does: the
// triangular-shaped cloud (TSC), i.e. the quadratic B-spline of width 3 cells in each direction
// (Hockney & Eastwood, "Computer Simulation Using Particles", 1988, ch. 5). In cell units with cell centres at integer + 1/2, a particle at s has
// its nearest centre c = floor(s) and offset d = s - (c + 1/2) in [-1/2, 1/2]; its weights on the
// cells c-1, c, c+1 are
//     w_-1 = (1/2 - d)^2 / 2,   w_0 = 3/4 - d^2,   w_+1 = (1/2 + d)^2 / 2,
// which sum to one exactly (partition of unity: particle volume and force are conserved) and are
// continuous with continuous first derivatives in s (void fraction and interpolated velocity do not
// jump when a particle crosses a cell face). Why this width: with the paper's cell of 3.33 d_p a
// particle occupies 1/37 of a cell; a one-cell kernel (CIC) makes the void fraction of a cell jump
// by that much each time a particle's centre crosses a face, the TSC spreads it over 27 cells
// (~10 d_p), which keeps the void fraction smooth and bounded without a separate smoothing pass.
// The same weights deposit (particle -> grid) and interpolate (grid -> particle): the two are
// transposes, which is what makes the drag momentum exchange exact.
#include <array>
#include <cmath>

namespace cgd {

/// Weights of one axis: cells first, first+1, first+2 (global, unwrapped indices).
struct AxisWeights {
  int first = 0;
  std::array<double, 3> w{};
};

/// TSC weights along one axis for position x (m), grid origin x0 (m) and spacing h (m).
inline AxisWeights tsc_weights(double x, double x0, double h) {
  const double s = (x - x0) / h;
  const double c = std::floor(s);
  const double d = s - c - 0.5;
  AxisWeights a;
  a.first = static_cast<int>(c) - 1;
  a.w[0] = 0.5 * (0.5 - d) * (0.5 - d);
  a.w[1] = 0.75 - d * d;
  a.w[2] = 0.5 * (0.5 + d) * (0.5 + d);
  return a;
}

}  // namespace cgd
