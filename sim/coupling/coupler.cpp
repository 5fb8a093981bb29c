#include "sim/coupling/coupler.hpp"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "core/error.hpp"

namespace cgd::coupling {

Coupler::Coupler(const CouplerSettings& settings, const fluid::FluidGrid& grid)
    : s_(settings), grid_(grid), rows_(RowOwners::gather(grid.comm(), grid.j0(), grid.ny_local())) {
  // the whole grid on every rank (exchange.hpp): the particles of a rank's DEM slab may lie in any row
  view_.cells = grid.cells();
  view_.spacing = grid.spacing();
  view_.j0 = 0;
  view_.ny_local = grid.ny();
  view_.ghost = fluid::FluidGrid::kGhost;
  owned_offset_ = static_cast<std::size_t>(grid.j0()) * grid.plane();
  const std::size_t storage = view_.storage_size();
  phi_.assign(storage, 0.0);
  cells_.assign(kRead * storage, 0.0);
  deposit_.assign(kDeposit * storage, 0.0);
  drift_ = settings.drag == DragLaw::Drift;
  if (drift_) {  // allocated only for the law that uses them
    drift_mass_.assign(storage, 0.0);
    for (int d = 0; d < 3; ++d) drift_mv_[d].assign(storage, 0.0);
    drift_cells_.assign(3 * storage, 0.0);
  }
  stress_ = settings.particle_stress.model != ParticleStressModel::None;
  if (stress_) {  // allocated only when the scene has a particle-phase pressure
    stress_mu_.assign(storage, 0.0);
    stress_potential_ = std::make_unique<StressPotential>(settings.particle_stress);
  }
}

void Coupler::particle_stress_accelerations(std::size_t n) {
  const fluid::FluidGrid& g = grid_;
  const int nx = g.nx(), nz = g.nz(), ny = g.ny_local();
  const StressPotential& mu = *stress_potential_;
  for (int j = 0; j < ny; ++j)
    for (int k = 0; k < nz; ++k)
      for (int i = 0; i < nx; ++i) {
        const std::size_t c = g.index(i, j, k) + owned_offset_;  // the owned rows, in the whole view
        stress_mu_[c] = mu(phi_[c]);
      }
  gather_rows(g.comm(), view_, rows_, stress_mu_.data(), 1);
  const double* m = stress_mu_.data();
  const double v_over_m = s_.particle_volume_m3 / s_.particle_mass_kg * s_.parcel_volume_factor;  // 1/rho_p
  pc_.stress_accel.assign(3 * n, 0.0);
  double sum[4] = {0.0, 0.0, 0.0, static_cast<double>(n)};
  for (std::size_t i = 0; i < n; ++i) {
    double grad[3] = {0.0, 0.0, 0.0};
    for_each_stencil_cell_gradient(view_, stencil_[i], [&](std::size_t c, double gx, double gy, double gz) {
      grad[0] += m[c] * gx;
      grad[1] += m[c] * gy;
      grad[2] += m[c] * gz;
    });
    for (int d = 0; d < 3; ++d) {
      pc_.stress_accel[3 * i + d] = -v_over_m * grad[d];
      sum[d] += pc_.stress_accel[3 * i + d];
    }
  }
  MPI_Allreduce(MPI_IN_PLACE, sum, 4, MPI_DOUBLE, MPI_SUM, g.comm());
  if (sum[3] > 0)
    for (std::size_t i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d) pc_.stress_accel[3 * i + d] -= sum[d] / sum[3];
}

void Coupler::drift_cell_velocity() {
  const fluid::FluidGrid& g = grid_;
  const std::size_t first = g.first_owned() + owned_offset_, last = first + g.owned_size();
  for (std::size_t c = first; c < last; ++c) {
    const double m = drift_mass_[c];
    double* out = &drift_cells_[3 * c];
    for (int d = 0; d < 3; ++d) out[d] = m > 0 ? drift_mv_[d][c] / m : cells_[kRead * c + d];  // empty: u_c, no slip
  }
  gather_rows(g.comm(), view_, rows_, drift_cells_.data(), 3);
}

void Coupler::cell_fields(const fluid::FluidState& state, bool with_phi) {
  // cell-centred velocity (mean of the two faces) and pressure gradient (central differences) on the
  // owned rows, then every other rank's rows and the periodic ghost rows: a rank's particles may be anywhere
  const fluid::FluidGrid& g = grid_;
  const int nx = g.nx(), nz = g.nz(), ny = g.ny_local();
  const auto& h = g.spacing();
  const auto& xp = g.x_plus();
  const auto& xm = g.x_minus();
  const auto& zp = g.z_plus();
  const auto& zm = g.z_minus();
  const double* pr = state.pressure.data();
  for (int j = 0; j < ny; ++j)
    for (int k = 0; k < nz; ++k)
      for (int i = 0; i < nx; ++i) {
        const std::size_t c = g.index(i, j, k);
        double* out = &cells_[kRead * (c + owned_offset_)];
        out[0] = 0.5 * (state.velocity[0][c] + state.velocity[0][g.index(xp[i], j, k)]);
        out[1] = 0.5 * (state.velocity[1][c] + state.velocity[1][g.index(i, j + 1, k)]);
        out[2] = 0.5 * (state.velocity[2][c] + state.velocity[2][g.index(i, j, zp[k])]);
        out[3] = (pr[g.index(xp[i], j, k)] - pr[g.index(xm[i], j, k)]) / (2.0 * h[0]);
        out[4] = (pr[g.index(i, j + 1, k)] - pr[g.index(i, j - 1, k)]) / (2.0 * h[1]);
        out[5] = (pr[g.index(i, j, zp[k])] - pr[g.index(i, j, zm[k])]) / (2.0 * h[2]);
        out[6] = with_phi ? phi_[c + owned_offset_] : 0.0;
      }
  gather_rows(g.comm(), view_, rows_, cells_.data(), kRead);
}

void Coupler::compute_drag(const dem::Particles& p, fluid::FluidState& state) {
  const fluid::FluidGrid& g = grid_;
  const std::size_t n = p.n_owned;
  const double vol = s_.particle_volume_m3 * s_.parcel_volume_factor;  // solid volume per (parcel) particle
  const double per_cell = vol / g.cell_volume();
  // 1. the particles' stencils (kept for step 4) and the solids fraction
  stencil_.resize(n);
  std::fill(phi_.begin(), phi_.end(), 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    stencil_[i] = make_stencil(view_, &p.x[3 * i]);
    for_each_stencil_cell(view_, stencil_[i], [&](std::size_t c, double w) { phi_[c] += per_cell * w; });
  }
  fold_ghost_rows(view_, phi_.data(), 1);
  reduce_rows_to_owners(g.comm(), view_, rows_, phi_.data(), 1);
  if (drift_) {  // the cells' mean particle velocity: the same weights, the same particle order as phi
    for (int d = 0; d < 3; ++d) std::fill(drift_mv_[d].begin(), drift_mv_[d].end(), 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      const double* v = &p.v[3 * i];
      for_each_stencil_cell(view_, stencil_[i], [&](std::size_t c, double w) {
        const double pw = per_cell * w;
        for (int d = 0; d < 3; ++d) drift_mv_[d][c] += pw * v[d];
      });
    }
    for (int d = 0; d < 3; ++d) {
      fold_ghost_rows(view_, drift_mv_[d].data(), 1);
      reduce_rows_to_owners(g.comm(), view_, rows_, drift_mv_[d].data(), 1);
    }
    drift_mass_ = phi_;  // the raw deposit sum_p V_p w_pc / V_cell, before the floor changes phi_
  }
  if (stress_) particle_stress_accelerations(n);  // from the raw deposit, before the floor changes phi_
  // void fraction with a conservative floor, on the owned rows (c: the fluid grid's index; c + off: the view's)
  const std::size_t first = g.first_owned(), last = first + g.owned_size(), off = owned_offset_;
  double excess = 0, room = 0, local_max = 0;
  long long floored = 0;
  for (std::size_t c = first; c < last; ++c) {
    const double eps = 1.0 - phi_[c + off];
    local_max = std::max(local_max, phi_[c + off]);
    if (eps < s_.void_fraction_floor) {
      excess += s_.void_fraction_floor - eps;
      ++floored;
    } else {
      room += eps - s_.void_fraction_floor;
    }
  }
  double sums[3] = {excess, room, static_cast<double>(floored)};
  MPI_Allreduce(MPI_IN_PLACE, sums, 3, MPI_DOUBLE, MPI_SUM, g.comm());
  MPI_Allreduce(&local_max, &max_phi_, 1, MPI_DOUBLE, MPI_MAX, g.comm());
  floored_ = static_cast<long long>(sums[2]);
  if (sums[0] > 0 && !(sums[1] > sums[0]))
    throw RunError("solids fraction too high to keep the void fraction above its floor " +
                   std::to_string(s_.void_fraction_floor) + " anywhere");
  const double take_back = sums[0] > 0 ? sums[0] / sums[1] : 0.0;
  for (std::size_t c = first; c < last; ++c) {
    double eps = 1.0 - phi_[c + off];
    if (eps < s_.void_fraction_floor) eps = s_.void_fraction_floor;
    else eps -= take_back * (eps - s_.void_fraction_floor);
    // one-way: the particles do not act on the fluid at all, neither by drag (B = 0) nor by the volume
    // they take (the fluid is solved with eps = 1; sim/coupled_step.hpp periodic_driving); eps serves the drag law
    state.void_fraction[c] = s_.two_way ? eps : 1.0;
    phi_[c + off] = 1.0 - eps;  // the solids fraction the fluid sees: used at the particles too
  }
  // 2. fluid at the particles (u, grad p, phi in one pass over the stencil), drag coefficients, and
  // their deposit B, B V
  cell_fields(state, true);
  if (drift_) {
    drift_cell_velocity();
    pc_.drift_shift.assign(3 * n, 0.0);
    pc_.cell_slip.assign(3 * n, 0.0);
  }
  pc_.beta.assign(n, 0.0);
  pc_.fluid_velocity.assign(3 * n, 0.0);
  pc_.pressure_gradient.assign(3 * n, 0.0);
  std::fill(deposit_.begin(), deposit_.end(), 0.0);
  const double* cf = cells_.data();
  double* dep = deposit_.data();
  visit_any_drag_law(s_.drag, s_.drag_params, s_.filtered, [&](const auto& law) {
    constexpr bool kDrift = is_drift_drag<std::decay_t<decltype(law)>>;
    for (std::size_t i = 0; i < n; ++i) {
      // all kRead values of a cell at once (vectorised; each sum in the kernel's cell order)
      alignas(64) double acc[kRead] = {0, 0, 0, 0, 0, 0, 0, 0};
      for_each_stencil_cell(view_, stencil_[i], [&](std::size_t c, double w) {
        const double* q = cf + kRead * c;
        for (int m = 0; m < kRead; ++m) acc[m] += w * q[m];
      });
      const double u[3] = {acc[0], acc[1], acc[2]}, gp[3] = {acc[3], acc[4], acc[5]};
      double phi_p = acc[6];
      if (!s_.drag_own_deposit) {  // the particle's own share of the phi it reads: per_cell sum_c w_c^2
        double w2 = 0;
        for_each_stencil_cell(view_, stencil_[i], [&](std::size_t, double w) { w2 += w * w; });
        phi_p = std::max(0.0, phi_p - per_cell * w2);
      }
      const double* v = &p.v[3 * i];
      double slip2 = 0;
      for (int d = 0; d < 3; ++d) {
        pc_.fluid_velocity[3 * i + d] = u[d];
        pc_.pressure_gradient[3 * i + d] = gp[d];
        const double s = u[d] - v[d];
        slip2 += s * s;
      }
      const double beta = law.beta_p(phi_p, std::sqrt(slip2));
      pc_.beta[i] = beta;
      double src[kDeposit] = {1.0, v[0], v[1], v[2]};  // bww * 1.0 == bww exactly
      if constexpr (kDrift) {
        // the cell slip s~ = u_p - vbar_p and the shift d = H(phi_p, |s~|/u_t) s~: the particle is driven as if its
        // velocity were v + d (the deposit below and compute_particle_forces)
        double vbar[3] = {0, 0, 0};
        for_each_stencil_cell(view_, stencil_[i], [&](std::size_t c, double w) {
          const double* q = &drift_cells_[3 * c];
          for (int d = 0; d < 3; ++d) vbar[d] += w * q[d];
        });
        double s[3], s2 = 0;
        for (int d = 0; d < 3; ++d) {
          s[d] = u[d] - vbar[d];
          s2 += s[d] * s[d];
        }
        const double H = law.cell_slip_correction(phi_p, std::sqrt(s2));
        for (int d = 0; d < 3; ++d) {
          pc_.cell_slip[3 * i + d] = s[d];
          pc_.drift_shift[3 * i + d] = H * s[d];
          src[1 + d] = v[d] + H * s[d];
        }
      }
      if (!s_.two_way) continue;
      const double bw = beta * per_cell;
      for_each_stencil_cell(view_, stencil_[i], [&](std::size_t c, double w) {
        double* q = dep + kDeposit * c;
        const double bww = bw * w;
        for (int m = 0; m < kDeposit; ++m) q[m] += bww * src[m];
      });
    }
  });
  // B and B V summed over the ranks onto the owned rows (one-way: nothing deposited, B = 0); the fluid's
  // ghost rows of B are its own to fill (solver.cpp)
  std::vector<double>& B = state.drag_coefficient;
  std::fill(B.begin(), B.end(), 0.0);
  if (s_.two_way) {
    fold_ghost_rows(view_, dep, kDeposit);
    reduce_rows_to_owners(g.comm(), view_, rows_, dep, kDeposit);
    for (std::size_t c = first; c < last; ++c) {
      const double* q = dep + kDeposit * (c + off);
      B[c] = q[0];
      for (int d = 0; d < 3; ++d) state.drag_velocity[d][c] = B[c] > 0 ? q[1 + d] / B[c] : 0.0;
    }
  }
}

void Coupler::compute_particle_forces(dem::Particles& p, fluid::FluidState& state) {
  // pc_ keeps compute_drag's quantities (snapshots); the new fluid level is interpolated and used at once
  if (stencil_.size() != p.n_owned)
    throw RunError("coupler: the particles changed between the drag and the particle forces of a fluid step");
  cell_fields(state, false);
  const double inv_rho_p = s_.particle_volume_m3 / s_.particle_mass_kg * s_.parcel_volume_factor;  // V/m
  const double* cf = cells_.data();
  // the drift law's particle velocity is shifted by d_p (compute_drag); every other law's loop is the plain one
  auto forces = [&](auto drift) {
    constexpr bool kDrift = decltype(drift)::value;
    for (std::size_t i = 0; i < p.n_owned; ++i) {
      alignas(64) double acc[kRead] = {0, 0, 0, 0, 0, 0, 0, 0};
      for_each_stencil_cell(view_, stencil_[i], [&](std::size_t c, double w) {
        const double* q = cf + kRead * c;
        for (int m = 0; m < kRead; ++m) acc[m] += w * q[m];
      });
      const double* u = acc;
      const double* gp = acc + 3;
      const double beta_over_rho = pc_.beta[i] * inv_rho_p;
      for (int d = 0; d < 3; ++d) {
        double a;
        if constexpr (kDrift)
          a = beta_over_rho * (u[d] - (p.v[3 * i + d] + pc_.drift_shift[3 * i + d])) + s_.particle_body_accel[d];
        else
          a = beta_over_rho * (u[d] - p.v[3 * i + d]) + s_.particle_body_accel[d];
        if (s_.pressure_gradient_force) a -= inv_rho_p * gp[d];
        p.a_ext[3 * i + d] = a;
      }
    }
  };
  if (drift_) forces(std::true_type{});
  else forces(std::false_type{});
  if (stress_)
    for (std::size_t k = 0; k < 3 * p.n_owned; ++k) p.a_ext[k] += pc_.stress_accel[k];
}

}  // namespace cgd::coupling
