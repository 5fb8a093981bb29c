#include "core/particle_stress.hpp"

namespace cgd {

StressPotential::StressPotential(const ParticleStressParams& s, int intervals) : s_(s), dphi_(1.0 / intervals) {
  // tau(s)/s^2 = P_s s^(beta - 2) / gap(s): bounded at s = 0 for beta >= 2 (the scene refuses less)
  const auto f = [&](double x) { return x > 0.0 ? harris_crighton_stress(s_, x) / (x * x) : (s_.beta == 2.0 ? s_.p_s_Pa / s_.phi_packed : 0.0); };
  constexpr int kSub = 16;  // Simpson on kSub sub-intervals of each table interval
  integral_.assign(static_cast<std::size_t>(intervals) + 1, 0.0);
  const double h = dphi_ / kSub;
  for (int k = 0; k < intervals; ++k) {
    const double a = k * dphi_;
    double sum = f(a) + f(a + dphi_);
    for (int m = 1; m < kSub; ++m) sum += (m % 2 ? 4.0 : 2.0) * f(a + m * h);
    integral_[static_cast<std::size_t>(k) + 1] = integral_[static_cast<std::size_t>(k)] + sum * h / 3.0;
  }
  // tau' rises monotonically toward phi_cp: bisection for tau'(phi_lim) = the cap
  if (std::isfinite(s_.max_stiffness_Pa) && harris_crighton_stiffness(s_, s_.phi_packed) > s_.max_stiffness_Pa) {
    double lo = 0.0, hi = s_.phi_packed;
    for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
      const double mid = 0.5 * (lo + hi);
      (harris_crighton_stiffness(s_, mid) > s_.max_stiffness_Pa ? hi : lo) = mid;
    }
    phi_lim_ = lo;
    mu_lim_ = uncapped(phi_lim_);
    slope_lim_ = harris_crighton_stiffness(s_, phi_lim_) / phi_lim_;
  }
}

double StressPotential::operator()(double phi) const {
  if (phi > phi_lim_) return mu_lim_ + slope_lim_ * (phi - phi_lim_);
  return uncapped(phi);
}

double StressPotential::uncapped(double phi) const {
  if (!(phi > 0.0)) return 0.0;
  const double x = std::min(phi, 1.0) / dphi_;
  const std::size_t k = std::min(static_cast<std::size_t>(x), integral_.size() - 2);
  const double t = x - static_cast<double>(k);
  const double integral = (1.0 - t) * integral_[k] + t * integral_[k + 1];
  return harris_crighton_stress(s_, phi) / phi + integral;
}

}  // namespace cgd
