#include "sim/coupling/coupler.hpp"

#include <mpi.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace cgd::coupling {

Coupler::Coupler(const CouplerSettings& settings, const fluid::FluidGrid& grid) : s_(settings), grid_(grid) {
  view_.cells = grid.cells();
  view_.spacing = grid.spacing();
  view_.j0 = grid.j0();
  view_.ny_local = grid.ny_local();
  view_.ghost = fluid::FluidGrid::kGhost;
  phi_ = grid.make_field();
  for (int d = 0; d < 3; ++d) {
    bv_[d] = grid.make_field();
    centre_u_[d] = grid.make_field();
    grad_p_[d] = grid.make_field();
  }
}

void Coupler::interpolate_fluid(const dem::Particles& p, fluid::FluidState& state, ParticleCoupling& out) {
  // cell-centred velocity (mean of the two faces) and pressure gradient (central differences) on the
  // owned rows, then the ghost rows from the neighbours: particles near a slab face need them
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
        centre_u_[0][c] = 0.5 * (state.velocity[0][c] + state.velocity[0][g.index(xp[i], j, k)]);
        centre_u_[1][c] = 0.5 * (state.velocity[1][c] + state.velocity[1][g.index(i, j + 1, k)]);
        centre_u_[2][c] = 0.5 * (state.velocity[2][c] + state.velocity[2][g.index(i, j, zp[k])]);
        grad_p_[0][c] = (pr[g.index(xp[i], j, k)] - pr[g.index(xm[i], j, k)]) / (2.0 * h[0]);
        grad_p_[1][c] = (pr[g.index(i, j + 1, k)] - pr[g.index(i, j - 1, k)]) / (2.0 * h[1]);
        grad_p_[2][c] = (pr[g.index(i, j, zp[k])] - pr[g.index(i, j, zm[k])]) / (2.0 * h[2]);
      }
  g.exchange_ghosts({centre_u_[0].data(), centre_u_[1].data(), centre_u_[2].data(), grad_p_[0].data(),
                     grad_p_[1].data(), grad_p_[2].data()});
  const std::size_t n = p.n_owned;
  out.fluid_velocity.assign(3 * n, 0.0);
  out.pressure_gradient.assign(3 * n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    double u[3] = {0, 0, 0}, gp[3] = {0, 0, 0};
    for_each_tsc_cell(view_, &p.x[3 * i], [&](std::size_t c, double w) {
      for (int d = 0; d < 3; ++d) {
        u[d] += w * centre_u_[d][c];
        gp[d] += w * grad_p_[d][c];
      }
    });
    for (int d = 0; d < 3; ++d) {
      out.fluid_velocity[3 * i + d] = u[d];
      out.pressure_gradient[3 * i + d] = gp[d];
    }
  }
}

void Coupler::compute_drag(const dem::Particles& p, fluid::FluidState& state) {
  const fluid::FluidGrid& g = grid_;
  const std::size_t n = p.n_owned;
  const double vol = s_.particle_volume_m3 * s_.parcel_volume_factor;  // solid volume per (parcel) particle
  const double per_cell = vol / g.cell_volume();
  // 1. solids fraction
  std::fill(phi_.begin(), phi_.end(), 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for_each_tsc_cell(view_, &p.x[3 * i], [&](std::size_t c, double w) { phi_[c] += per_cell * w; });
  accumulate_ghosts(g.comm(), view_, {phi_.data()});
  // void fraction with a conservative floor
  const std::size_t first = g.first_owned(), last = first + g.owned_size();
  double excess = 0, room = 0, local_max = 0;
  long long floored = 0;
  for (std::size_t c = first; c < last; ++c) {
    const double eps = 1.0 - phi_[c];
    local_max = std::max(local_max, phi_[c]);
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
    double eps = 1.0 - phi_[c];
    if (eps < s_.void_fraction_floor) eps = s_.void_fraction_floor;
    else eps -= take_back * (eps - s_.void_fraction_floor);
    // one-way: the particles do not act on the fluid at all, neither by drag (B = 0) nor by the volume
    // they take (the fluid is solved with eps = 1; sim/coupled_step.hpp periodic_driving); eps serves the drag law
    state.void_fraction[c] = s_.two_way ? eps : 1.0;
    phi_[c] = 1.0 - eps;  // the solids fraction the fluid sees: used at the particles too
  }
  g.exchange_ghosts({phi_.data()});
  // 2. fluid at the particles, drag coefficients
  interpolate_fluid(p, state, pc_);
  pc_.beta.assign(n, 0.0);
  std::vector<double>& B = state.drag_coefficient;
  std::fill(B.begin(), B.end(), 0.0);
  for (int d = 0; d < 3; ++d) std::fill(bv_[d].begin(), bv_[d].end(), 0.0);
  visit_any_drag_law(s_.drag, s_.drag_params, s_.filtered, [&](const auto& law) {
    for (std::size_t i = 0; i < n; ++i) {
      double phi_p = 0;
      for_each_tsc_cell(view_, &p.x[3 * i], [&](std::size_t c, double w) { phi_p += w * phi_[c]; });
      double slip2 = 0;
      for (int d = 0; d < 3; ++d) {
        const double s = pc_.fluid_velocity[3 * i + d] - p.v[3 * i + d];
        slip2 += s * s;
      }
      const double beta = law.beta_p(phi_p, std::sqrt(slip2));
      pc_.beta[i] = beta;
      if (!s_.two_way) continue;
      const double bw = beta * per_cell;
      const double* v = &p.v[3 * i];
      for_each_tsc_cell(view_, &p.x[3 * i], [&](std::size_t c, double w) {
        B[c] += bw * w;
        bv_[0][c] += bw * w * v[0];
        bv_[1][c] += bw * w * v[1];
        bv_[2][c] += bw * w * v[2];
      });
    }
  });
  if (s_.two_way) {
    accumulate_ghosts(g.comm(), view_, {B.data(), bv_[0].data(), bv_[1].data(), bv_[2].data()});
    for (std::size_t c = first; c < last; ++c)
      for (int d = 0; d < 3; ++d) state.drag_velocity[d][c] = B[c] > 0 ? bv_[d][c] / B[c] : 0.0;
  }
}

void Coupler::compute_particle_forces(dem::Particles& p, fluid::FluidState& state) {
  // pc_ keeps compute_drag's quantities (snapshots); the new fluid level goes to new_level_
  interpolate_fluid(p, state, new_level_);
  const double inv_rho_p = s_.particle_volume_m3 / s_.particle_mass_kg * s_.parcel_volume_factor;  // V/m
  for (std::size_t i = 0; i < p.n_owned; ++i) {
    const double beta_over_rho = pc_.beta[i] * inv_rho_p;
    for (int d = 0; d < 3; ++d) {
      double a = beta_over_rho * (new_level_.fluid_velocity[3 * i + d] - p.v[3 * i + d]) + s_.particle_body_accel[d];
      if (s_.pressure_gradient_force) a -= inv_rho_p * new_level_.pressure_gradient[3 * i + d];
      p.a_ext[3 * i + d] = a;
    }
  }
}

}  // namespace cgd::coupling
