#pragma once
// The particle-phase pressure of a coarse-grid run (issue 28; docs/models.md "Particle-phase pressure"): an
// isotropic solids stress tau(phi) of the cell's solids fraction whose gradient acts on the particles (or
// parcels), as the filtered two-fluid models close their particle phase (Igci et al. 2008, AIChE J. 54:1431)
// and as MP-PIC keeps parcels from packing beyond what the cell allows (Snider 2001).
//
// Form of Harris & Crighton (1994, J. Fluid Mech. 266:243), in MP-PIC's notation (Snider 2001,
// J. Comput. Phys. 170:523, eq. 13; also Auzerais, Jackson & Russel 1988):
//
//     tau(phi) = P_s phi^beta / max(phi_cp - phi, eps (1 - phi))
//
// P_s (Pa) sets the scale, beta (Snider: 2 to 5) how fast it rises, phi_cp is close packing, where the
// denominator would vanish, and eps (Snider: 1e-7) keeps it finite at and beyond phi_cp.
//
// Discretisation (sim/coupling/coupler.hpp). The force per unit volume of the particle phase is -grad tau, i.e.
// per particle -V_p grad tau / phi (Snider's -grad tau / (rho_p phi) per unit mass). It is taken as the exact
// gradient of a discrete free energy of the cells,
//
//     E = sum_c V_c psi(phi_c),   psi'' = tau' / phi,   so   F_p = -dE/dx_p = -V_p sum_c mu(phi_c) grad w_pc,
//     mu(phi) = psi'(phi) = integral_0^phi tau'(s)/s ds = tau(phi)/phi + integral_0^phi tau(s)/s^2 ds,
//
// with w_pc the deposit's TSC weights: in the continuum limit sum_c mu_c grad w_pc -> grad mu = tau' grad phi / phi
// = grad tau / phi, as wanted. Being a gradient of E, which grows for any uneven split of the particles between
// neighbouring cells (psi is convex), the force damps every grid-scale mode, the odd-even one included; the cell-centred
// central difference of tau (the MP-PIC cell form) cannot see that mode, and a coarse run with it at P_s = 30 Pa fell
// into alternating layers of phi 0.40 and 0.00 (docs/closure.md). beta >= 2 keeps the integral finite at phi = 0.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace cgd {

enum class ParticleStressModel { None, HarrisCrighton };

struct ParticleStressParams {
  ParticleStressModel model = ParticleStressModel::None;
  double p_s_Pa = 1.0;       // P_s
  double beta = 3.0;         // exponent of phi, >= 2
  double phi_packed = 0.6;   // phi_cp
  double epsilon = 1e-7;     // the denominator's floor, relative to 1 - phi
  // Set by the engine, not a scene key (sim/coupled_step.cpp): the largest tau' (Pa) an explicit force held over the
  // longest fluid step can carry, rho_p (C h / dt_fluid,max)^2 with C = numerics.particle_stress_courant; above the
  // phi where tau' reaches it, mu continues linearly (StressPotential). Infinite: no cap.
  double max_stiffness_Pa = std::numeric_limits<double>::infinity();
};

/// The Harris-Crighton denominator max(phi_cp - phi, eps (1 - phi)) and its derivative in phi.
struct HarrisCrightonGap {
  double value, derivative;
};
inline HarrisCrightonGap harris_crighton_gap(const ParticleStressParams& s, double phi) {
  const double open = s.phi_packed - phi, floor = s.epsilon * (1.0 - phi);
  return open < floor ? HarrisCrightonGap{floor, -s.epsilon} : HarrisCrightonGap{open, -1.0};
}

/// tau(phi) of the Harris-Crighton form above, Pa (0 for phi <= 0).
inline double harris_crighton_stress(const ParticleStressParams& s, double phi) {
  if (!(phi > 0.0)) return 0.0;
  return s.p_s_Pa * std::pow(phi, s.beta) / harris_crighton_gap(s, phi).value;
}

/// tau'(phi) of the Harris-Crighton form, Pa (0 for phi <= 0).
inline double harris_crighton_stiffness(const ParticleStressParams& s, double phi) {
  if (!(phi > 0.0)) return 0.0;
  const HarrisCrightonGap gap = harris_crighton_gap(s, phi);
  return s.p_s_Pa * (s.beta * std::pow(phi, s.beta - 1.0) / gap.value -
                     std::pow(phi, s.beta) * gap.derivative / (gap.value * gap.value));
}

/// mu(phi) = tau(phi)/phi + integral_0^phi tau(s)/s^2 ds (Pa), the potential whose kernel gradient is the force
/// (above): the integral tabulated once on a uniform grid of phi in [0, 1] (Simpson's rule on each interval's
/// 16 sub-intervals), linearly interpolated, tau/phi exact. Relative error of the integral below 1e-6 of mu away
/// from phi_cp (tests/unit/test_particle_stress.cpp). With a finite max_stiffness_Pa: above phi_lim, where tau'
/// reaches it (bisection), mu(phi) = mu(phi_lim) + (tau'(phi_lim)/phi_lim)(phi - phi_lim) -- the law's stiffness
/// held at the cap, so that the explicit force stays stable into and beyond close packing.
class StressPotential {
 public:
  explicit StressPotential(const ParticleStressParams& s, int intervals = 8192);
  double operator()(double phi) const;
  const ParticleStressParams& params() const { return s_; }
  /// phi_lim of the stiffness cap (1 when there is none, or the law never reaches it below phi_cp).
  double stiffness_limit_phi() const { return phi_lim_; }

 private:
  double uncapped(double phi) const;
  ParticleStressParams s_;
  double phi_lim_ = 1.0, mu_lim_ = 0.0, slope_lim_ = 0.0;
  double dphi_ = 0;
  std::vector<double> integral_;  // integral_0^{k dphi} tau(s)/s^2 ds, k = 0 .. intervals
};

}  // namespace cgd
