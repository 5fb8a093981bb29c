#include "sim/fluid/solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "core/error.hpp"

namespace cgd::fluid {

namespace {

/// Times a scope into one phase when timers are in use.
class MaybePhase {
 public:
  MaybePhase(PhaseTimers* t, std::size_t phase) {
    if (t) scoped_.emplace(*t, phase);
  }

 private:
  std::optional<ScopedPhase> scoped_;
};

/// Loop over the owned faces of direction D: f(c, c_minus) with c the face's cell (the face is its lower
/// D-face) and c_minus the cell below it in D.
template <int D, class F>
void for_owned_faces(const FluidGrid& g, F&& f) {
  const int nx = g.nx(), nz = g.nz(), rows = g.ny_local();
  const std::size_t sy = g.plane();
  const auto& zm = g.z_minus();
  for (int j = 0; j < rows; ++j)
    for (int k = 0; k < nz; ++k) {
      const std::size_t row = g.index(0, j, k);
      const std::size_t row_zm = g.index(0, j, zm[k]);
      periodic_row(
          nx, [&](int i, [[maybe_unused]] int ip, [[maybe_unused]] int im) __attribute__((always_inline)) {
            const std::size_t c = row + i;
            const std::size_t cm = D == 0 ? row + im : D == 1 ? c - sy : row_zm + i;
            f(c, cm);
          });
    }
}

}  // namespace

FluidSolver::FluidSolver(const FluidGrid& grid, const FluidSettings& settings, PhaseTimers* timers)
    : grid_(grid), settings_(settings), pressure_(grid_, settings.pressure), timers_(timers) {
  if (!(settings_.density_kg_m3 > 0.0)) throw InputError("fluid.density must be > 0 (kg/m^3)");
  if (!(settings_.viscosity_Pa_s >= 0.0)) throw InputError("fluid.viscosity must be >= 0 (Pa s)");
  state_.void_fraction = grid_.make_field(1.0);
  state_.void_fraction_old = grid_.make_field(1.0);
  state_.pressure = grid_.make_field();
  state_.drag_coefficient = grid_.make_field();
  for (int d = 0; d < 3; ++d) {
    state_.velocity[d] = grid_.make_field();
    state_.drag_velocity[d] = grid_.make_field();
    state_.body_force[d] = grid_.make_field();
    state_.explicit_rate_old[d] = grid_.make_field();
    flux_[d] = grid_.make_field();
    rate_[d] = grid_.make_field();
    q_[d] = grid_.make_field();
    K_[d] = grid_.make_field();
  }
  rhs_ = grid_.make_field();
  if (timers_) {
    phase_predictor_ = timers_->add("fluid predictor");
    phase_pressure_ = timers_->add("fluid pressure");
    phase_correction_ = timers_->add("fluid correction");
  }
}

void FluidSolver::set_pressure_settings(const PressureSettings& s) {
  settings_.pressure = s;
  pressure_.set_settings(s);
}

void FluidSolver::reset_history() {
  state_.void_fraction_old = state_.void_fraction;
  for (auto& f : state_.explicit_rate_old) std::fill(f.begin(), f.end(), 0.0);
  state_.dt_previous_s = 0.0;
}

// F^n = -rho_f div(M u) + div(eps^n tau^n) on the owned faces, M = eps^n_f u^n,
// tau = mu_f (grad u + grad u^T).
// Both are written as differences of fluxes: advective fluxes on the faces of the momentum control
// volumes, eps tau at the cell centres (normal stresses) and on the cell edges (shear stresses). Each
// flux is computed once and read by the two control volumes it separates.
void FluidSolver::explicit_rate() {
  const FluidGrid& g = grid_;
  const int nx = g.nx(), nz = g.nz(), rows = g.ny_local();
  const std::size_t sy = g.plane();
  const auto &zp = g.z_plus(), &zm = g.z_minus();
  const auto& h = g.spacing();
  const double ihx = 1.0 / h[0], ihy = 1.0 / h[1], ihz = 1.0 / h[2];
  const double rho = settings_.density_kg_m3, mu = settings_.viscosity_Pa_s;
  const double* __restrict eps = state_.void_fraction_old.data();
  const double* __restrict ux = state_.velocity[0].data();
  const double* __restrict uy = state_.velocity[1].data();
  const double* __restrict uz = state_.velocity[2].data();
  double* __restrict Mx = flux_[0].data();
  double* __restrict My = flux_[1].data();
  double* __restrict Mz = flux_[2].data();
  // Stresses times eps (Pa), in work fields that predictor() overwrites afterwards:
  //   Sxx, Syy, Szz = 2 mu eps du_d/dx_d at the cell centres, eps of the cell;
  //   Exy at the edge (i h_x, j h_y, (k+1/2) h_z) = mu eps_e (du_x/dy + du_y/dx), eps_e the mean of the
  //   four cells around the edge; Exz at (i h_x, (j+1/2) h_y, k h_z) and Eyz at ((i+1/2) h_x, j h_y, k h_z)
  //   likewise. Index of an edge: the cell (i, j, k) whose lower faces meet there.
  double* __restrict Sxx = q_[0].data();
  double* __restrict Syy = q_[1].data();
  double* __restrict Szz = q_[2].data();
  double* __restrict Exy = K_[0].data();
  double* __restrict Exz = K_[1].data();
  double* __restrict Eyz = K_[2].data();

  // Mass fluxes on the faces of rows [-1, ny_local]; normal stresses on the cells of rows [-1, ny_local);
  // shear stresses on the edges of rows [0, ny_local] (u_x and u_z read E_xy, E_yz one row up).
  for (int j = -1; j <= rows; ++j)
    for (int k = 0; k < nz; ++k) {
      const std::size_t row = g.index(0, j, k), row_zm = g.index(0, j, zm[k]);
      periodic_row(
          nx, [&](int i, [[maybe_unused]] int ip, [[maybe_unused]] int im) __attribute__((always_inline)) {
            const std::size_t c = row + i;
            Mx[c] = 0.5 * (eps[row + im] + eps[c]) * ux[c];
            My[c] = 0.5 * (eps[c - sy] + eps[c]) * uy[c];
            Mz[c] = 0.5 * (eps[row_zm + i] + eps[c]) * uz[c];
          });
    }
  const double two_mu = 2.0 * mu, quarter_mu = 0.25 * mu;
  for (int j = -1; j < rows; ++j)
    for (int k = 0; k < nz; ++k) {
      const std::size_t row = g.index(0, j, k), row_zp = g.index(0, j, zp[k]);
      periodic_row(
          nx, [&](int i, [[maybe_unused]] int ip, [[maybe_unused]] int im) __attribute__((always_inline)) {
            const std::size_t c = row + i;
            const double two_mu_eps = two_mu * eps[c];
            Sxx[c] = two_mu_eps * ((ux[row + ip] - ux[c]) * ihx);
            Syy[c] = two_mu_eps * ((uy[c + sy] - uy[c]) * ihy);
            Szz[c] = two_mu_eps * ((uz[row_zp + i] - uz[c]) * ihz);
          });
    }
  for (int j = 0; j <= rows; ++j)
    for (int k = 0; k < nz; ++k) {
      const std::size_t row = g.index(0, j, k), row_zm = g.index(0, j, zm[k]);
      periodic_row(
          nx, [&](int i, [[maybe_unused]] int ip, [[maybe_unused]] int im) __attribute__((always_inline)) {
            const std::size_t c = row + i, cxm = row + im, czm = row_zm + i;
            const std::size_t cym = c - sy, cxym = cxm - sy, cxzm = row_zm + im, cyzm = czm - sy;
            Exy[c] = quarter_mu * (eps[c] + eps[cxm] + eps[cym] + eps[cxym]) *
                     ((ux[c] - ux[cym]) * ihy + (uy[c] - uy[cxm]) * ihx);
            Exz[c] = quarter_mu * (eps[c] + eps[cxm] + eps[czm] + eps[cxzm]) *
                     ((ux[c] - ux[czm]) * ihz + (uz[c] - uz[cxm]) * ihx);
            Eyz[c] = quarter_mu * (eps[c] + eps[cym] + eps[czm] + eps[cyzm]) *
                     ((uy[c] - uy[czm]) * ihz + (uz[c] - uz[cym]) * ihy);
          });
    }

  double* __restrict Fx = rate_[0].data();
  double* __restrict Fy = rate_[1].data();
  double* __restrict Fz = rate_[2].data();
  for (int j = 0; j < rows; ++j)
    for (int k = 0; k < nz; ++k) {
      const int kp = zp[k], km = zm[k];
      const std::size_t row = g.index(0, j, k);
      const std::size_t row_zp = g.index(0, j, kp), row_zm = g.index(0, j, km);
      periodic_row(
          nx, [=](int i, [[maybe_unused]] int ip, [[maybe_unused]] int im) __attribute__((always_inline)) {
            const std::size_t c = row + i, cxp = row + ip, cxm = row + im;
            const std::size_t cyp = c + sy, cym = c - sy, czp = row_zp + i, czm = row_zm + i;
            // --- u_x on the face (i, j, k): control volume from cell centre i-1 to cell centre i.
            {
              const double fxx_hi = 0.25 * (Mx[c] + Mx[cxp]) * (ux[c] + ux[cxp]);
              const double fxx_lo = 0.25 * (Mx[cxm] + Mx[c]) * (ux[cxm] + ux[c]);
              const double fyx_hi = 0.25 * (My[cxm + sy] + My[cyp]) * (ux[c] + ux[cyp]);
              const double fyx_lo = 0.25 * (My[cxm] + My[c]) * (ux[cym] + ux[c]);
              const double fzx_hi = 0.25 * (Mz[row_zp + im] + Mz[czp]) * (ux[c] + ux[czp]);
              const double fzx_lo = 0.25 * (Mz[cxm] + Mz[c]) * (ux[czm] + ux[c]);
              const double adv = (fxx_hi - fxx_lo) * ihx + (fyx_hi - fyx_lo) * ihy + (fzx_hi - fzx_lo) * ihz;
              const double visc =
                  (Sxx[c] - Sxx[cxm]) * ihx + (Exy[cyp] - Exy[c]) * ihy + (Exz[czp] - Exz[c]) * ihz;
              Fx[c] = -rho * adv + visc;
            }
            // --- u_y on the face (i, j, k): control volume from cell centre j-1 to cell centre j.
            {
              const double fxy_hi = 0.25 * (Mx[cxp - sy] + Mx[cxp]) * (uy[c] + uy[cxp]);
              const double fxy_lo = 0.25 * (Mx[cym] + Mx[c]) * (uy[cxm] + uy[c]);
              const double fyy_hi = 0.25 * (My[c] + My[cyp]) * (uy[c] + uy[cyp]);
              const double fyy_lo = 0.25 * (My[cym] + My[c]) * (uy[cym] + uy[c]);
              const double fzy_hi = 0.25 * (Mz[czp - sy] + Mz[czp]) * (uy[c] + uy[czp]);
              const double fzy_lo = 0.25 * (Mz[cym] + Mz[c]) * (uy[czm] + uy[c]);
              const double adv = (fxy_hi - fxy_lo) * ihx + (fyy_hi - fyy_lo) * ihy + (fzy_hi - fzy_lo) * ihz;
              const double visc =
                  (Exy[cxp] - Exy[c]) * ihx + (Syy[c] - Syy[cym]) * ihy + (Eyz[czp] - Eyz[c]) * ihz;
              Fy[c] = -rho * adv + visc;
            }
            // --- u_z on the face (i, j, k): control volume from cell centre k-1 to cell centre k.
            {
              const double fxz_hi = 0.25 * (Mx[row_zm + ip] + Mx[cxp]) * (uz[c] + uz[cxp]);
              const double fxz_lo = 0.25 * (Mx[czm] + Mx[c]) * (uz[cxm] + uz[c]);
              const double fyz_hi = 0.25 * (My[czm + sy] + My[cyp]) * (uz[c] + uz[cyp]);
              const double fyz_lo = 0.25 * (My[czm] + My[c]) * (uz[cym] + uz[c]);
              const double fzz_hi = 0.25 * (Mz[c] + Mz[czp]) * (uz[c] + uz[czp]);
              const double fzz_lo = 0.25 * (Mz[czm] + Mz[c]) * (uz[czm] + uz[c]);
              const double adv = (fxz_hi - fxz_lo) * ihx + (fyz_hi - fyz_lo) * ihy + (fzz_hi - fzz_lo) * ihz;
              const double visc =
                  (Exz[cxp] - Exz[c]) * ihx + (Eyz[cyp] - Eyz[c]) * ihy + (Szz[c] - Szz[czm]) * ihz;
              Fz[c] = -rho * adv + visc;
            }
          });
    }
}

// q, K and the provisional flux w = eps_f q / a on the owned faces; the pressure right-hand side.
void FluidSolver::predictor(double dt) {
  const FluidGrid& g = grid_;
  const double rho = settings_.density_kg_m3;
  const double r = state_.dt_previous_s > 0.0 ? dt / state_.dt_previous_s : 0.0;
  const double c_new = 1.0 + 0.5 * r, c_old = -0.5 * r;  // AB2 weights (Euler when r = 0)
  const double* eps = state_.void_fraction.data();
  const double* eps_old = state_.void_fraction_old.data();
  const double* B = state_.drag_coefficient.data();
  const bool field = settings_.body_force_field;
  // eps > 0 and B >= 0 keep a = rho_f eps_f/dt + B_f and K positive (an SPD pressure operator).
  double invalid = 0.0;
  for (std::size_t c = g.first_owned(); c < g.first_owned() + g.owned_size(); ++c)
    if (!(eps[c] > 0.0 && B[c] >= 0.0)) invalid += 1.0;
  invalid = g.sum(invalid);
  if (invalid > 0.0)
    throw RunError("fluid step: " + std::to_string(static_cast<long long>(invalid)) +
                   " cells with void fraction <= 0 or a negative or non-finite drag coefficient");
  for (int d = 0; d < 3; ++d) {
    const double f = settings_.body_force_per_fluid_volume_N_m3[d];
    const double* u = state_.velocity[d].data();
    const double* V = state_.drag_velocity[d].data();
    const double* F = rate_[d].data();
    const double* F_old = state_.explicit_rate_old[d].data();
    const double* f_field = state_.body_force[d].data();
    double *q = q_[d].data(), *K = K_[d].data(), *w = flux_[d].data();
    auto face = [&](std::size_t c, std::size_t cm) {
      const double eps_f = 0.5 * (eps[cm] + eps[c]);
      const double eps_old_f = 0.5 * (eps_old[cm] + eps_old[c]);
      const double B_f = 0.5 * (B[cm] + B[c]);
      const double BV_f = 0.5 * (B[cm] * V[cm] + B[c] * V[c]);
      double qf = rho * eps_old_f * u[c] / dt + c_new * F[c] + c_old * F_old[c] + eps_f * f + BV_f;
      if (field) qf += f_field[c];
      const double a = rho * eps_f / dt + B_f;
      q[c] = qf;
      K[c] = eps_f * eps_f / a;
      w[c] = eps_f * qf / a;
    };
    if (d == 0) for_owned_faces<0>(g, face);
    if (d == 1) for_owned_faces<1>(g, face);
    if (d == 2) for_owned_faces<2>(g, face);
  }
  g.exchange_ghosts({flux_[1].data()}, 1);  // D needs w_y on the slab's upper face

  const int nx = g.nx(), nz = g.nz(), rows = g.ny_local();
  const std::size_t sy = g.plane();
  const auto& zp = g.z_plus();
  const auto& h = g.spacing();
  const double ihx = 1.0 / h[0], ihy = 1.0 / h[1], ihz = 1.0 / h[2];
  const double *wx = flux_[0].data(), *wy = flux_[1].data(), *wz = flux_[2].data();
  double scale = 0.0;
  for (int j = 0; j < rows; ++j)
    for (int k = 0; k < nz; ++k) {
      const std::size_t row = g.index(0, j, k), row_zp = g.index(0, j, zp[k]);
      periodic_row(
          nx, [&](int i, [[maybe_unused]] int ip, [[maybe_unused]] int im) __attribute__((always_inline)) {
            const std::size_t c = row + i, cxp = row + ip, czp = row_zp + i;
            const double deps_dt = (eps[c] - eps_old[c]) / dt;
            rhs_[c] =
                (wx[cxp] - wx[c]) * ihx + (wy[c + sy] - wy[c]) * ihy + (wz[czp] - wz[c]) * ihz + deps_dt;
            const double terms = std::abs(deps_dt) + (std::abs(wx[cxp]) + std::abs(wx[c])) * ihx +
                                 (std::abs(wy[c + sy]) + std::abs(wy[c])) * ihy +
                                 (std::abs(wz[czp]) + std::abs(wz[c])) * ihz;
            scale = std::max(scale, terms);
          });
    }
  report_.rhs_term_scale_1_s = g.max(scale);
  if (!std::isfinite(report_.rhs_term_scale_1_s))
    throw RunError(
        "fluid step: non-finite provisional velocity or void fraction (dt = " + std::to_string(dt) + " s)");
}

void FluidSolver::correction(double dt) {
  const FluidGrid& g = grid_;
  const double rho = settings_.density_kg_m3;
  const double* eps = state_.void_fraction.data();
  const double* B = state_.drag_coefficient.data();
  const double* p = state_.pressure.data();
  for (int d = 0; d < 3; ++d) {
    const double ih = 1.0 / g.spacing()[d];
    const double* q = q_[d].data();
    double* u = state_.velocity[d].data();
    auto face = [&](std::size_t c, std::size_t cm) {
      const double eps_f = 0.5 * (eps[cm] + eps[c]);
      const double a = rho * eps_f / dt + 0.5 * (B[cm] + B[c]);
      u[c] = (q[c] - eps_f * (p[c] - p[cm]) * ih) / a;
    };
    if (d == 0) for_owned_faces<0>(g, face);
    if (d == 1) for_owned_faces<1>(g, face);
    if (d == 2) for_owned_faces<2>(g, face);
  }
  g.exchange_ghosts({state_.velocity[0].data(), state_.velocity[1].data(), state_.velocity[2].data()});

  // Continuity check with the new velocities: (eps^{n+1} - eps^n)/dt + D(eps_f u^{n+1}).
  const int nx = g.nx(), nz = g.nz(), rows = g.ny_local();
  const std::size_t sy = g.plane();
  const auto &zp = g.z_plus(), &zm = g.z_minus();
  const auto& h = g.spacing();
  const double ihx = 1.0 / h[0], ihy = 1.0 / h[1], ihz = 1.0 / h[2];
  const double* eps_old = state_.void_fraction_old.data();
  const double *ux = state_.velocity[0].data(), *uy = state_.velocity[1].data(),
               *uz = state_.velocity[2].data();
  double res = 0.0, scale = 0.0;
  for (int j = 0; j < rows; ++j)
    for (int k = 0; k < nz; ++k) {
      const std::size_t row = g.index(0, j, k), row_zp = g.index(0, j, zp[k]), row_zm = g.index(0, j, zm[k]);
      periodic_row(
          nx, [&](int i, [[maybe_unused]] int ip, [[maybe_unused]] int im) __attribute__((always_inline)) {
            const std::size_t c = row + i, cxp = row + ip, czp = row_zp + i;
            const double fx_lo = 0.5 * (eps[row + im] + eps[c]) * ux[c];
            const double fx_hi = 0.5 * (eps[c] + eps[cxp]) * ux[cxp];
            const double fy_lo = 0.5 * (eps[c - sy] + eps[c]) * uy[c];
            const double fy_hi = 0.5 * (eps[c] + eps[c + sy]) * uy[c + sy];
            const double fz_lo = 0.5 * (eps[row_zm + i] + eps[c]) * uz[c];
            const double fz_hi = 0.5 * (eps[c] + eps[czp]) * uz[czp];
            const double deps_dt = (eps[c] - eps_old[c]) / dt;
            const double r = deps_dt + (fx_hi - fx_lo) * ihx + (fy_hi - fy_lo) * ihy + (fz_hi - fz_lo) * ihz;
            res = std::max(res, std::abs(r));
            scale = std::max(scale, std::abs(deps_dt) + (std::abs(fx_hi) + std::abs(fx_lo)) * ihx +
                                        (std::abs(fy_hi) + std::abs(fy_lo)) * ihy +
                                        (std::abs(fz_hi) + std::abs(fz_lo)) * ihz);
          });
    }
  report_.continuity_residual_1_s = g.max(res);
  const double global_scale = g.max(scale);
  report_.continuity_relative = global_scale > 0.0 ? report_.continuity_residual_1_s / global_scale : 0.0;
  if (!std::isfinite(report_.continuity_residual_1_s))
    throw RunError("fluid step: non-finite velocity after the pressure correction");
}

StepReport FluidSolver::step(double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s))
    throw RunError("fluid step: time step must be positive and finite, got " + std::to_string(dt_s));
  report_ = StepReport{};
  report_.dt_s = dt_s;
  {
    MaybePhase phase(timers_, phase_predictor_);
    auto& s = state_;
    grid_.exchange_ghosts({s.void_fraction.data(), s.void_fraction_old.data(), s.drag_coefficient.data(),
                           s.drag_velocity[0].data(), s.drag_velocity[1].data(), s.drag_velocity[2].data(),
                           s.velocity[0].data(), s.velocity[1].data(), s.velocity[2].data()});
    explicit_rate();
    predictor(dt_s);
  }
  {
    MaybePhase phase(timers_, phase_pressure_);
    if (!settings_.warm_start) std::fill(state_.pressure.begin(), state_.pressure.end(), 0.0);
    const double floor = settings_.roundoff_floor * report_.rhs_term_scale_1_s;
    report_.pressure = pressure_.solve(K_, rhs_, state_.pressure, floor);
    if (std::abs(report_.pressure.rhs_mean_removed) >
        settings_.rhs_mean_tolerance * report_.rhs_term_scale_1_s)
      throw RunError("fluid step: the pressure equation's right-hand side has mean " +
                     std::to_string(report_.pressure.rhs_mean_removed) + " 1/s against terms of size " +
                     std::to_string(report_.rhs_term_scale_1_s) +
                     " 1/s: the total void fraction changed during the step (particle volume not conserved "
                     "by the coupling)");
  }
  {
    MaybePhase phase(timers_, phase_correction_);
    correction(dt_s);
    state_.void_fraction_old = state_.void_fraction;
    std::swap(state_.explicit_rate_old, rate_);
    state_.dt_previous_s = dt_s;
  }
  return report_;
}

double FluidSolver::viscous_dt_limit() const {
  const double nu = settings_.viscosity_Pa_s / settings_.density_kg_m3;
  double s = 0.0;
  for (double hd : grid_.spacing()) s += 1.0 / (hd * hd);
  if (nu <= 0.0) return std::numeric_limits<double>::infinity();
  return settings_.viscous_safety / (4.0 * nu * s);
}

double FluidSolver::max_dt(double courant, double dt_cap_s) const {
  const FluidGrid& g = grid_;
  const int nx = g.nx(), nz = g.nz(), rows = g.ny_local();
  const std::size_t sy = g.plane();
  const auto& zp = g.z_plus();
  const auto& h = g.spacing();
  const double *ux = state_.velocity[0].data(), *uy = state_.velocity[1].data(),
               *uz = state_.velocity[2].data();
  double rate = 0.0;  // max over cells of sum_d |u_d| / h_d, |u_d| the mean of the two faces' magnitudes
  for (int j = 0; j < rows; ++j)
    for (int k = 0; k < nz; ++k) {
      const std::size_t row = g.index(0, j, k), row_zp = g.index(0, j, zp[k]);
      periodic_row(
          nx, [&](int i, [[maybe_unused]] int ip, [[maybe_unused]] int im) __attribute__((always_inline)) {
            const std::size_t c = row + i;
            const double s = 0.5 * (std::abs(ux[c]) + std::abs(ux[row + ip])) / h[0] +
                             0.5 * (std::abs(uy[c]) + std::abs(uy[c + sy])) / h[1] +
                             0.5 * (std::abs(uz[c]) + std::abs(uz[row_zp + i])) / h[2];
            rate = std::max(rate, s);
          });
    }
  rate = g.max(rate);
  double dt = std::min(dt_cap_s, viscous_dt_limit());
  if (rate > 0.0) dt = std::min(dt, courant / rate);
  return dt;
}

FlowAverages FluidSolver::averages() {
  const FluidGrid& g = grid_;
  auto& s = state_;
  g.exchange_ghosts(
      {s.void_fraction.data(), s.velocity[0].data(), s.velocity[1].data(), s.velocity[2].data()}, 1);
  const double rho = settings_.density_kg_m3, vol = g.cell_volume();
  const double* eps = s.void_fraction.data();
  double local[8] = {0, 0, 0, 0, 0, 0, 0, 0};  // sum eps, sum eps_f u (3), sum eps_f u^2 (3)
  const std::size_t lo = g.first_owned(), hi = lo + g.owned_size();
  for (std::size_t c = lo; c < hi; ++c) local[0] += eps[c];
  for (int d = 0; d < 3; ++d) {
    const double* u = s.velocity[d].data();
    double m = 0.0, e = 0.0;
    auto face = [&](std::size_t c, std::size_t cm) {
      const double eu = 0.5 * (eps[cm] + eps[c]) * u[c];
      m += eu;
      e += eu * u[c];
    };
    if (d == 0) for_owned_faces<0>(g, face);
    if (d == 1) for_owned_faces<1>(g, face);
    if (d == 2) for_owned_faces<2>(g, face);
    local[1 + d] = m;
    local[4 + d] = e;
  }
  double global[8];
  MPI_Allreduce(local, global, 7, MPI_DOUBLE, MPI_SUM, g.comm());
  const double n = static_cast<double>(g.cells_total());
  FlowAverages a;
  a.void_fraction = global[0] / n;
  for (int d = 0; d < 3; ++d) {
    a.eps_velocity[d] = global[1 + d] / n;
    a.fluid_velocity[d] = a.eps_velocity[d] / a.void_fraction;
    a.momentum_kg_m_s[d] = rho * global[1 + d] * vol;
    a.kinetic_energy_J += 0.5 * rho * global[4 + d] * vol;
  }
  return a;
}

void FluidSolver::fill_file_order(FileOrderFields& out) {
  const FluidGrid& g = grid_;
  auto& s = state_;
  g.exchange_ghosts({s.void_fraction.data(), s.velocity[0].data(), s.velocity[1].data(), s.velocity[2].data()}, 1);
  const int nx = g.nx(), nz = g.nz(), rows = g.ny_local();
  const auto& zm = g.z_minus();
  const double* eps = s.void_fraction.data();
  const std::size_t n = g.owned_size(), sy = g.plane();
  const auto& zp = g.z_plus();
  out.void_fraction.resize(n);
  out.pressure.resize(n);
  out.velocity.resize(3 * n);
  out.eps_velocity.resize(3 * n);
  const double *ux = s.velocity[0].data(), *uy = s.velocity[1].data(), *uz = s.velocity[2].data();
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < rows; ++j) {
      const std::size_t row = g.index(0, j, k), row_zp = g.index(0, j, zp[k]), row_zm = g.index(0, j, zm[k]);
      const std::size_t file_row = (static_cast<std::size_t>(k) * rows + j) * nx;
      periodic_row(
          nx, [&](int i, int ip, int im) __attribute__((always_inline)) {
            const std::size_t c = row + i, o = file_row + i;
            out.void_fraction[o] = s.void_fraction[c];
            out.pressure[o] = s.pressure[c];
            out.velocity[3 * o + 0] = 0.5 * (ux[c] + ux[row + ip]);
            out.velocity[3 * o + 1] = 0.5 * (uy[c] + uy[c + sy]);
            out.velocity[3 * o + 2] = 0.5 * (uz[c] + uz[row_zp + i]);
            // face fluxes eps_f u_f on the low and high face of cell c along each axis
            const double fx_lo = 0.5 * (eps[row + im] + eps[c]) * ux[c];
            const double fx_hi = 0.5 * (eps[c] + eps[row + ip]) * ux[row + ip];
            const double fy_lo = 0.5 * (eps[c - sy] + eps[c]) * uy[c];
            const double fy_hi = 0.5 * (eps[c] + eps[c + sy]) * uy[c + sy];
            const double fz_lo = 0.5 * (eps[row_zm + i] + eps[c]) * uz[c];
            const double fz_hi = 0.5 * (eps[c] + eps[row_zp + i]) * uz[row_zp + i];
            out.eps_velocity[3 * o + 0] = 0.5 * (fx_lo + fx_hi);
            out.eps_velocity[3 * o + 1] = 0.5 * (fy_lo + fy_hi);
            out.eps_velocity[3 * o + 2] = 0.5 * (fz_lo + fz_hi);
          });
    }
}

}  // namespace cgd::fluid
