#pragma once
// A resolved run of one scene: assembles the effects the scene calls for into one time loop and
// owns the run directory (design.md "Files"): scene.toml, snapshots/snap_<step>.h5, series.h5,
// checkpoint.h5, run.xmf and the completion marker DONE, written last.
#include <mpi.h>

#include <string>

#include "core/scene.hpp"
#include "sim/dem/system.hpp"

namespace cgd {

/// DEM settings of a scene (contact parameters, drive, time step). Throws InputError for a
/// combination this build cannot simulate.
dem::DemSettings dem_settings_from_scene(const Scene& scene);

/// Periodic sedimentation driving of a scene that solves the fluid (models.md "Periodic sedimentation
/// driving"). A mean pressure gradient G is removed from the solved pressure; the fluid gets the body
/// force eps (rho_f g - G) and each particle m g - V_p G when the pressure-gradient force is on (m g
/// alone when it is off), chosen so that the fluid carries what the coupling makes it carry:
///   two-way, pressure-gradient force on:  G = rho_mix g, rho_mix = <phi> rho_p + <eps> rho_f:
///       fluid eps (rho_f - rho_mix) g, particles g (1 - rho_mix/rho_p); net force on the box zero;
///   two-way, pressure-gradient force off: G = rho_mix g / <eps> (the particles feel no pressure, so the
///       fluid alone must carry the mixture's weight): fluid eps (rho_f - rho_mix/<eps>) g, particles g;
///       net force <eps> V (rho_f - rho_mix/<eps>) g + <phi> V rho_p g = 0;
///   one-way: the particles do not act on the fluid (no drag on it, and it is solved with eps = 1,
///       coupler.hpp), so it carries no particle weight: G = rho_f g (hydrostatic), the fluid gets no body
///       force and a fluid at rest stays at rest; the particles see the fluid's buoyancy, g (1 - rho_f/rho_p)
///       (force on: the same as a quiescent fluid), or g (force off), and settle at their single-particle
///       drag balance. With rho_mix instead, nothing balanced the fluid's eps (rho_f - rho_mix) g (-565 m/s^2
///       at <phi> = 0.05) and the fluid accelerated without bound.
/// Without the pressure-gradient force (two-way) the fluid's -eps grad p' (p' the periodic part) has no
/// counterpart on the particles, so the mixture momentum is not conserved exactly (model A needs the force).
struct PeriodicDriving {
  Vec3 pressure_gradient_mean_Pa_m{};   // G, removed from the solved pressure
  Vec3 fluid_body_force_N_m3{};         // rho_f g - G, per fluid volume (the fluid gets eps times it)
  Vec3 particle_body_accel_m_s2{};      // g - V_p G / m with the pressure-gradient force on, else g
};
PeriodicDriving periodic_driving(const Scene& scene);

struct RunSettings {
  std::string output_dir;
  bool restart = false;
  bool quiet = false;          // no progress line
  std::string tool = "cgd-generate";
};

/// Runs the scene to its end time; returns normally when done. Throws InputError before writing
/// anything for bad input (an existing run directory without --restart, a missing checkpoint),
/// and RunError for a failed run, after writing a diagnostic snapshot and keeping the last
/// checkpoint. SIGINT/SIGTERM write a checkpoint and end the run with RunError ("interrupted").
/// With settings.restart: refuses (InputError, nothing written) a scene whose physics differs from the
/// checkpoint's (restart_differences), an end time before the checkpoint, and does nothing for a run
/// that is already complete (DONE written and the checkpoint at the end).
void run_scene(const Scene& scene, const RunSettings& settings, MPI_Comm comm);

/// The scene a restart of the run in output_dir continues: `scene` with the checkpoint's scene name, after
/// checking that only the keys restart_may_change differ. Throws InputError otherwise. Collective.
Scene restart_scene(const Scene& scene, const std::string& output_dir, MPI_Comm comm);

}  // namespace cgd
