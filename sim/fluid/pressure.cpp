#include "sim/fluid/pressure.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <string>

#include "core/error.hpp"

namespace cgd::fluid {

PressureSolver::PressureSolver(const FluidGrid& grid, const PressureSettings& settings)
    : grid_(grid), settings_(settings) {
  plan();
  r_ = grid_.make_field();
  z_ = grid_.make_field();
  d_ = grid_.make_field();
  q_ = grid_.make_field();
  scale_ = grid_.make_field(1.0);
}

PressureSolver::~PressureSolver() {
  if (forward_) fftw_destroy_plan(forward_);
  if (backward_) fftw_destroy_plan(backward_);
  if (fft_buf_) fftw_free(fft_buf_);
}

void PressureSolver::set_settings(const PressureSettings& s) {
  const bool replan = s.fft_measure != settings_.fft_measure;
  settings_ = s;
  if (replan) plan();
}

void PressureSolver::plan() {
  if (forward_) fftw_destroy_plan(forward_);
  if (backward_) fftw_destroy_plan(backward_);
  if (fft_buf_) fftw_free(fft_buf_);
  fftw_mpi_init();
  const int nx = grid_.nx(), ny = grid_.ny(), nz = grid_.nz();
  const ptrdiff_t nxc = nx / 2 + 1;
  ptrdiff_t n0 = 0, start0 = 0;
  alloc_complex_ =
      fftw_mpi_local_size_3d_transposed(ny, nz, nxc, grid_.comm(), &n0, &start0, &local_kz_, &kz0_);
  if (n0 != grid_.ny_local() || start0 != grid_.j0())
    throw RunError("pressure solver: FFTW slab differs from the fluid grid's slab");
  fft_buf_ = fftw_alloc_real(2 * std::max<ptrdiff_t>(alloc_complex_, 1));
  const unsigned flags = settings_.fft_measure ? FFTW_MEASURE : FFTW_ESTIMATE;
  auto* cbuf = reinterpret_cast<fftw_complex*>(fft_buf_);
  forward_ =
      fftw_mpi_plan_dft_r2c_3d(ny, nz, nx, fft_buf_, cbuf, grid_.comm(), flags | FFTW_MPI_TRANSPOSED_OUT);
  backward_ =
      fftw_mpi_plan_dft_c2r_3d(ny, nz, nx, cbuf, fft_buf_, grid_.comm(), flags | FFTW_MPI_TRANSPOSED_IN);
  if (!forward_ || !backward_) throw RunError("pressure solver: FFTW-MPI could not plan the transforms");

  // Exact eigenvalues of the 7-point periodic Laplacian; the transposed spectral layout is
  // (k_z local, k_y, k_x), k_x in [0, n_x/2].
  const auto& h = grid_.spacing();
  auto symbol = [](int k, int n, double hd) {
    return (2.0 * std::cos(2.0 * std::numbers::pi * k / n) - 2.0) / (hd * hd);
  };
  std::vector<double> lx(nxc), ly(ny), lz(nz);
  for (int k = 0; k < nxc; ++k) lx[k] = symbol(k, nx, h[0]);
  for (int k = 0; k < ny; ++k) ly[k] = symbol(k, ny, h[1]);
  for (int k = 0; k < nz; ++k) lz[k] = symbol(k, nz, h[2]);
  const double n_total = static_cast<double>(grid_.cells_total());  // FFTW is unnormalised
  inv_eigen_.assign(static_cast<std::size_t>(local_kz_) * ny * nxc, 0.0);
  std::size_t o = 0;
  for (ptrdiff_t kz = 0; kz < local_kz_; ++kz)
    for (int ky = 0; ky < ny; ++ky)
      for (ptrdiff_t kx = 0; kx < nxc; ++kx, ++o) {
        const double lambda = lx[kx] + ly[ky] + lz[kz0_ + kz];
        // lambda = 0 only for k = 0 (the constants): that mode is the null space and is set to zero.
        inv_eigen_[o] = (kx == 0 && ky == 0 && kz0_ + kz == 0) ? 0.0 : 1.0 / (-lambda * n_total);
      }
}

// z = factor * (-L)^-1 r (zero-mean z), through the FFT.
namespace {
void copy_in(const FluidGrid& g, const std::vector<double>& r, const double* scale, double* buf) {
  const int nx = g.nx(), nz = g.nz(), rows = g.ny_local();
  const std::size_t padded = 2 * (static_cast<std::size_t>(nx) / 2 + 1);
  for (int j = 0; j < rows; ++j)
    for (int k = 0; k < nz; ++k) {
      const std::size_t src = g.index(0, j, k);
      double* dst = buf + (static_cast<std::size_t>(j) * nz + k) * padded;
      if (scale)
        for (int i = 0; i < nx; ++i) dst[i] = scale[src + i] * r[src + i];
      else
        std::memcpy(dst, &r[src], nx * sizeof(double));
    }
}
void copy_out(const FluidGrid& g, const double* buf, const double* scale, double factor,
              std::vector<double>& z) {
  const int nx = g.nx(), nz = g.nz(), rows = g.ny_local();
  const std::size_t padded = 2 * (static_cast<std::size_t>(nx) / 2 + 1);
  for (int j = 0; j < rows; ++j)
    for (int k = 0; k < nz; ++k) {
      const std::size_t dst = g.index(0, j, k);
      const double* src = buf + (static_cast<std::size_t>(j) * nz + k) * padded;
      if (scale)
        for (int i = 0; i < nx; ++i) z[dst + i] = factor * scale[dst + i] * src[i];
      else
        for (int i = 0; i < nx; ++i) z[dst + i] = factor * src[i];
    }
}
}  // namespace

namespace {
// out = sign * D(K G p) on the owned cells; returns the local sum of p * out.
template <bool WithDot>
double stencil(const FluidGrid& g, const std::array<std::vector<double>, 3>& K, const std::vector<double>& p,
               std::vector<double>& out, double sign) {
  const int nx = g.nx(), nz = g.nz(), rows = g.ny_local();
  const auto& h = g.spacing();
  const double cx = sign / (h[0] * h[0]), cy = sign / (h[1] * h[1]), cz = sign / (h[2] * h[2]);
  const std::ptrdiff_t sy = static_cast<std::ptrdiff_t>(g.plane());
  const auto &zp = g.z_plus(), &zm = g.z_minus();
  const double* __restrict Kx = K[0].data();
  const double* __restrict Ky = K[1].data();
  const double* __restrict Kz = K[2].data();
  const double* __restrict P = p.data();
  double* __restrict A = out.data();
  double dot = 0.0;
  for (int j = 0; j < rows; ++j)
    for (int k = 0; k < nz; ++k) {
      const std::size_t row = g.index(0, j, k);
      const std::size_t row_zp = g.index(0, j, zp[k]), row_zm = g.index(0, j, zm[k]);
      periodic_row(
          nx, [&](int i, int ip, int im) __attribute__((always_inline)) {
            const std::size_t c = row + i;
            const double pc = P[c];
            const double ax = Kx[row + ip] * (P[row + ip] - pc) - Kx[c] * (pc - P[row + im]);
            const double ay = Ky[c + sy] * (P[c + sy] - pc) - Ky[c] * (pc - P[c - sy]);
            const double az = Kz[row_zp + i] * (P[row_zp + i] - pc) - Kz[c] * (pc - P[row_zm + i]);
            const double a = cx * ax + cy * ay + cz * az;
            A[c] = a;
            if constexpr (WithDot) dot += pc * a;
          });
    }
  return dot;
}
}  // namespace

void PressureSolver::solve_constant_coefficient(const std::vector<double>& r, std::vector<double>& z,
                                                double c) {
  fft_inverse(r, nullptr, z, -1.0 / c);  // (c L)^-1 = -(1/c) (-L)^-1
}

void PressureSolver::fft_inverse(const std::vector<double>& r, const double* scale, std::vector<double>& z,
                                 double factor) {
  copy_in(grid_, r, scale, fft_buf_);
  fftw_execute(forward_);
  auto* cbuf = reinterpret_cast<fftw_complex*>(fft_buf_);
  for (std::size_t o = 0; o < inv_eigen_.size(); ++o) {
    cbuf[o][0] *= inv_eigen_[o];
    cbuf[o][1] *= inv_eigen_[o];
  }
  fftw_execute(backward_);
  copy_out(grid_, fft_buf_, scale, factor, z);
}

double PressureSolver::precondition(const std::vector<double>& r, std::vector<double>& z) {
  switch (settings_.preconditioner) {
    case Preconditioner::ArithmeticMean:
    case Preconditioner::HarmonicMean:
      fft_inverse(r, nullptr, z, 1.0 / coefficient_);
      break;
    case Preconditioner::DiagonalScaled:
      fft_inverse(r, scale_.data(), z, 1.0);
      break;
    case Preconditioner::Sandwich:
      fft_inverse(r, nullptr, t_, 1.0);
      grid_.exchange_ghosts({t_.data()}, 1);
      stencil<false>(grid_, K_inverse_, t_, u_, -1.0);
      fft_inverse(u_, nullptr, z, 1.0);
      break;
  }
  return dot(r, z);
}

void PressureSolver::apply_operator(const std::array<std::vector<double>, 3>& K, const std::vector<double>& p,
                                    std::vector<double>& out) const {
  stencil<false>(grid_, K, p, out, 1.0);
}

double PressureSolver::dot(const std::vector<double>& a, const std::vector<double>& b) const {
  double s = 0.0;
  const std::size_t lo = grid_.first_owned(), hi = lo + grid_.owned_size();
  for (std::size_t c = lo; c < hi; ++c) s += a[c] * b[c];
  return grid_.sum(s);
}

double PressureSolver::max_abs(const std::vector<double>& a) const {
  double m = 0.0;
  const std::size_t lo = grid_.first_owned(), hi = lo + grid_.owned_size();
  for (std::size_t c = lo; c < hi; ++c) m = std::max(m, std::abs(a[c]));
  return grid_.max(m);
}

double PressureSolver::mean(const std::vector<double>& a) const {
  double s = 0.0;
  const std::size_t lo = grid_.first_owned(), hi = lo + grid_.owned_size();
  for (std::size_t c = lo; c < hi; ++c) s += a[c];
  return grid_.sum(s) / static_cast<double>(grid_.cells_total());
}

PressureStats PressureSolver::solve(std::array<std::vector<double>, 3>& K, std::vector<double>& b,
                                    std::vector<double>& p, double absolute_floor) {
  PressureStats st;
  const std::size_t lo = grid_.first_owned(), hi = lo + grid_.owned_size();
  // Solvability: the periodic operator's range is the zero-mean fields.
  st.rhs_mean_removed = mean(b);
  for (std::size_t c = lo; c < hi; ++c) b[c] -= st.rhs_mean_removed;
  st.rhs_max = max_abs(b);
  if (st.rhs_max == 0.0) {
    std::fill(p.begin(), p.end(), 0.0);
    return st;
  }
  const double threshold = std::max(settings_.tolerance * st.rhs_max, absolute_floor);
  grid_.exchange_ghosts({K[1].data()}, 1);

  // Preconditioner data.
  if (settings_.preconditioner == Preconditioner::DiagonalScaled) {
    const int nx = grid_.nx(), nz = grid_.nz(), rows = grid_.ny_local();
    const std::size_t sy = grid_.plane();
    const auto &xp = grid_.x_plus(), &zp = grid_.z_plus();
    for (int j = 0; j < rows; ++j)
      for (int k = 0; k < nz; ++k) {
        const std::size_t row = grid_.index(0, j, k), row_zp = grid_.index(0, j, zp[k]);
        for (int i = 0; i < nx; ++i) {
          const std::size_t c = row + i;
          const double cell_K =
              (K[0][c] + K[0][row + xp[i]] + K[1][c] + K[1][c + sy] + K[2][c] + K[2][row_zp + i]) / 6.0;
          scale_[c] = 1.0 / std::sqrt(cell_K);
        }
      }
  } else if (settings_.preconditioner == Preconditioner::Sandwich) {
    for (int d = 0; d < 3; ++d) {
      if (K_inverse_[d].size() != K[d].size()) K_inverse_[d].assign(K[d].size(), 0.0);
      for (std::size_t c = lo; c < hi; ++c) K_inverse_[d][c] = 1.0 / K[d][c];
    }
    grid_.exchange_ghosts({K_inverse_[1].data()}, 1);
    if (t_.size() != r_.size()) {
      t_ = grid_.make_field();
      u_ = grid_.make_field();
    }
  } else {
    double s = 0.0, s_inv = 0.0;
    for (int d = 0; d < 3; ++d)
      for (std::size_t c = lo; c < hi; ++c) {
        s += K[d][c];
        s_inv += 1.0 / K[d][c];
      }
    const double faces = 3.0 * static_cast<double>(grid_.cells_total());
    coefficient_ = settings_.preconditioner == Preconditioner::ArithmeticMean ? grid_.sum(s) / faces
                                                                              : faces / grid_.sum(s_inv);
  }

  // PCG on (-A) p = -b (SPD on zero-mean fields); r holds -(b - A p).
  grid_.exchange_ghosts({p.data()}, 1);
  apply_operator(K, p, r_);
  double r_max = 0.0;
  for (std::size_t c = lo; c < hi; ++c) {
    r_[c] -= b[c];
    r_max = std::max(r_max, std::abs(r_[c]));
  }
  r_max = grid_.max(r_max);
  int it = 0;
  if (r_max > threshold) {
    double rz = precondition(r_, z_);
    std::copy(z_.begin() + lo, z_.begin() + hi, d_.begin() + lo);
    for (it = 1;; ++it) {
      if (it > settings_.max_iterations)
        throw RunError("pressure solver: PCG did not converge in " +
                       std::to_string(settings_.max_iterations) + " iterations (max residual " +
                       std::to_string(r_max / st.rhs_max) + " of max|b|)");
      grid_.exchange_ghosts({d_.data()}, 1);
      const double dq = grid_.sum(stencil<true>(grid_, K, d_, q_, -1.0));  // q = -A d
      const double alpha = rz / dq;
      if (!std::isfinite(alpha)) throw RunError("pressure solver: PCG breakdown (non-finite step length)");
      double* __restrict pp = p.data();
      double* __restrict rr = r_.data();
      const double* __restrict dd = d_.data();
      const double* __restrict qq = q_.data();
      double m = 0.0;
      for (std::size_t c = lo; c < hi; ++c) {
        pp[c] += alpha * dd[c];
        rr[c] -= alpha * qq[c];
        m = std::max(m, std::abs(rr[c]));
      }
      r_max = grid_.max(m);
      if (r_max <= threshold) break;
      const double rz_new = precondition(r_, z_);
      const double beta = rz_new / rz;
      rz = rz_new;
      double* __restrict d = d_.data();
      const double* __restrict z = z_.data();
      for (std::size_t c = lo; c < hi; ++c) d[c] = z[c] + beta * d[c];
    }
  }
  st.iterations = it;
  // Zero-mean p (the null space), valid ghosts, and the true residual.
  const double p_mean = mean(p);
  for (std::size_t c = lo; c < hi; ++c) p[c] -= p_mean;
  grid_.exchange_ghosts({p.data()});
  apply_operator(K, p, r_);
  double r_true = 0.0;
  for (std::size_t c = lo; c < hi; ++c) r_true = std::max(r_true, std::abs(r_[c] - b[c]));
  st.residual = grid_.max(r_true) / st.rhs_max;
  return st;
}

}  // namespace cgd::fluid
