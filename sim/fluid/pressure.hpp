#pragma once
// Variable-coefficient pressure Poisson solve on the periodic MAC grid (models.md, model A):
//
//     D(K G p) = b,     (G p)_d = (p_c - p_{c - e_d}) / h_d on the lower d-face of cell c,
//                       (D f)_c = sum_d (f_{d, c + e_d} - f_{d, c}) / h_d,
//
// i.e. the 7-point operator sum_d [K_{d,c+e_d} (p_{c+e_d} - p_c) - K_{d,c} (p_c - p_{c-e_d})] / h_d^2 with
// K >= 0 on the faces (K = eps_f^2 / (rho_f eps_f / dt + B_f) in the fluid step). Periodic: constants are
// the null space. The solver removes the mean of b (the equation is solvable only for zero-mean b; the
// removed amount is reported so the caller can judge it) and returns the zero-mean p.
//
// Method: preconditioned conjugate gradients on the SPD operator -D K G (restricted to zero-mean
// vectors). The preconditioner is an FFT solve of the constant-coefficient problem with the discrete
// operator's exact eigenvalues,
//     lambda(k) = sum_d (2 cos(2 pi k_d / n_d) - 2) / h_d^2,
// so for constant K it is the exact inverse and PCG stops after one iteration. Variants, all exact for
// constant K (K_c: the cell mean of its six face values):
//   ArithmeticMean: M = -mean(K) L;  HarmonicMean: M = -harmonic_mean(K) L. PCG's iterates do not change
//     when the preconditioner is multiplied by a constant, so these two take the same iterations (kept
//     both to show it); neither sees where K is small.
//   DiagonalScaled: M^-1 = S^-1/2 (-L)^-1 S^-1/2, S = diag(K_c): follows the local size of K.
//   Sandwich (default): M^-1 = (-L)^-1 (-D K^-1 G) (-L)^-1, two FFT solves around the operator with the
//     inverse coefficient. It is the exact inverse in 1-D up to a constant flux (there D K G p = b gives
//     K G p = G L^-1 b + c), SPD on zero-mean fields, and follows the jumps of K in the direction of G.
// Iterations to 1e-10 (tests/unit/test_fluid.cpp, bench/fluid_bench.cpp): smooth K in [0.1, 1.9]:
// 43 / 43 / 12 / 9; moving eps in [0.4, 1] with B dt/rho_f up to 30: 101 / 101 / 21 / 13; random
// smoothed eps in [0.6, 1], B dt/rho_f up to 30, warm start: 70 / - / 47 / 11. Cost per iteration:
// 2 FFTs, 2 FFTs, 2 FFTs, 4 FFTs + one stencil; the sandwich is the fastest per solve.
// Stopping test: max|b - A p| <= max(tolerance * max|b|, absolute_floor) (the max norm: continuity must
// hold in every cell); the reported residual is recomputed from p at the end (not the recursive one).
//
// FFTs: FFTW-MPI r2c/c2r on the (n_y, n_z, n_x) real array, in place, FFTW_MPI_TRANSPOSED_OUT/IN so the
// spectral side is (k_z, k_y, k_x) distributed over k_z and no transpose back is done. Planning is
// FFTW_ESTIMATE by default: deterministic plans give bit-identical results on every run (restarts and
// the 1-vs-2-rank comparison rely on reproducibility) and planning costs nothing; FFTW_MEASURE can be
// chosen (bench/fluid_bench.cpp compares the two).
#include <fftw3-mpi.h>

#include <array>
#include <vector>

#include "sim/fluid/grid.hpp"

namespace cgd::fluid {

enum class Preconditioner { ArithmeticMean, HarmonicMean, DiagonalScaled, Sandwich };

struct PressureSettings {
  double tolerance = 1e-10;  // relative: max|b - A p| <= tolerance * max|b|
  int max_iterations = 500;  // RunError beyond this
  Preconditioner preconditioner = Preconditioner::Sandwich;
  bool fft_measure = false;  // FFTW_MEASURE instead of FFTW_ESTIMATE (see above)
};

struct PressureStats {
  int iterations = 0;
  double residual = 0.0;          // max|b - A p| / max|b| after the solve (0 when b = 0)
  double rhs_max = 0.0;           // max|b| after the mean was removed
  double rhs_mean_removed = 0.0;  // mean of b as given (units of b)
};

class PressureSolver {
 public:
  /// Plans the FFTs (collective over grid.comm()). The grid must outlive the solver.
  PressureSolver(const FluidGrid& grid, const PressureSettings& settings);
  ~PressureSolver();
  PressureSolver(const PressureSolver&) = delete;
  PressureSolver& operator=(const PressureSolver&) = delete;

  const PressureSettings& settings() const { return settings_; }
  void set_settings(const PressureSettings& s);

  /// Solve D(K G p) = b. `K` holds the three face fields (grid storage; the owned faces are read, the
  /// y-ghost planes of K[1] are refreshed here). `b` (owned cells; its mean is removed in place) and
  /// `p` (initial guess on entry, zero-mean solution on exit with valid y-ghosts). `absolute_floor` (units
  /// of b): the residual below which the answer is round-off anyway (e.g. 1e-14 times the size of the
  /// terms b was a difference of). Collective. Throws RunError when not converged in max_iterations.
  PressureStats solve(std::array<std::vector<double>, 3>& K, std::vector<double>& b, std::vector<double>& p,
                      double absolute_floor = 0.0);

  /// out = D(K G p) on the owned cells (p's y-ghosts of width 1 and K[1]'s upper ghost plane must be valid).
  void apply_operator(const std::array<std::vector<double>, 3>& K, const std::vector<double>& p,
                      std::vector<double>& out) const;

  /// z = (c L)^-1 r on the zero-mean subspace, with L the constant-coefficient 7-point Laplacian (owned
  /// cells; the mean of r is ignored, z has zero mean). Collective. Exposed for tests.
  void solve_constant_coefficient(const std::vector<double>& r, std::vector<double>& z, double c);

 private:
  void plan();
  void fft_inverse(const std::vector<double>& r, const double* scale, std::vector<double>& z, double factor);
  double precondition(const std::vector<double>& r, std::vector<double>& z);  // z = M^-1 r; returns (r, z)
  double dot(const std::vector<double>& a, const std::vector<double>& b) const;
  double max_abs(const std::vector<double>& a) const;
  double mean(const std::vector<double>& a) const;

  const FluidGrid& grid_;
  PressureSettings settings_;
  ptrdiff_t alloc_complex_ = 0, local_kz_ = 0, kz0_ = 0;
  double* fft_buf_ = nullptr;  // padded real (ny_local, nz, 2(nx/2+1)) / complex (local_kz, ny, nx/2+1)
  fftw_plan forward_ = nullptr, backward_ = nullptr;
  std::vector<double> inv_eigen_;  // 1 / (-lambda(k) N) per local complex entry, 0 for k = 0
  // PCG work vectors (grid storage) and the preconditioner's cell scaling / coefficient.
  std::vector<double> r_, z_, d_, q_, scale_, t_, u_;
  std::array<std::vector<double>, 3> K_inverse_;
  double coefficient_ = 1.0;
};

}  // namespace cgd::fluid
