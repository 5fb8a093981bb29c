#pragma once
// The names of a snapshot's contents and of the common root attributes and /params every cgd file carries
// (docs/schema-run.md "Common root attributes", "/params" and "Snapshot"), each spelled once: the writer
// (core/output.cpp: write_common, write_snapshot), the reader (core/snapshot.cpp: read_snapshot), run.xmf
// (core/xdmf.cpp) and the checkpoint's header (core/checkpoint.cpp) use these. The checkpoint's own names are
// at the top of core/checkpoint.cpp, the series' columns in core/series.cpp.
namespace cgd::schema::names {

// common root attributes (schema::write_common)
inline constexpr const char* kRoot = "/";
inline constexpr const char* kFormat = "cgd_format";
inline constexpr const char* kFormatVersion = "cgd_format_version";
inline constexpr const char* kCodeVersion = "code_version";
inline constexpr const char* kCreated = "created";
inline constexpr const char* kScene = "scene";

// /params: the group, and the attributes a reader takes back (the writer spells the others once, in
// write_params)
inline constexpr const char* kParams = "/params";
inline constexpr const char* kSceneName = "scene_name";
inline constexpr const char* kHasFluid = "has_fluid";
inline constexpr const char* kBoxSize = "box_size_m";
inline constexpr const char* kGravity = "gravity_m_s2";
inline constexpr const char* kDiameter = "diameter_m";
inline constexpr const char* kDensity = "density_kg_m3";
inline constexpr const char* kSolidsFraction = "solids_fraction";
inline constexpr const char* kParcelSize = "parcel_size";
inline constexpr const char* kFluidDensity = "fluid_density_kg_m3";
inline constexpr const char* kFluidViscosity = "fluid_viscosity_Pa_s";
inline constexpr const char* kCoupling = "coupling";
inline constexpr const char* kDrag = "drag";
inline constexpr const char* kPressureGradientForce = "pressure_gradient_force";
inline constexpr const char* kUt = "u_t_m_s";
inline constexpr const char* kLChar = "l_char_m";
inline constexpr const char* kTref = "t_ref_s";

// snapshot: root attributes
inline constexpr const char* kTime = "time";
inline constexpr const char* kStep = "step";

// snapshot: /particles, N rows each
inline constexpr const char* kParticles = "/particles";
inline constexpr const char* kId = "/particles/id";
inline constexpr const char* kPosition = "/particles/position";
inline constexpr const char* kVelocity = "/particles/velocity";
inline constexpr const char* kAngularVelocity = "/particles/angular_velocity";
inline constexpr const char* kParticleDiameter = "/particles/diameter";
inline constexpr const char* kDragCoefficient = "/particles/drag_coefficient";
inline constexpr const char* kFluidVelocityAtParticles = "/particles/fluid_velocity";
inline constexpr const char* kPressureGradient = "/particles/pressure_gradient";
inline constexpr const char* kPressureGradientMean = "pressure_gradient_mean";  // of /particles

// snapshot: /fluid, fields (n_z, n_y, n_x[, 3])
inline constexpr const char* kFluid = "/fluid";
inline constexpr const char* kCells = "cells";      // of /fluid
inline constexpr const char* kSpacing = "spacing";  // of /fluid
inline constexpr const char* kOrigin = "origin";    // of /fluid
inline constexpr const char* kLayout = "layout";    // of /fluid
inline constexpr const char* kVoidFraction = "/fluid/void_fraction";
inline constexpr const char* kCellVelocity = "/fluid/velocity";
inline constexpr const char* kPressure = "/fluid/pressure";
inline constexpr const char* kEpsVelocity = "/fluid/eps_velocity";

// attributes of groups and datasets
inline constexpr const char* kTimeLevel = "time_level";  // of /particles and /fluid
inline constexpr const char* kUnit = "unit";              // of every dataset
inline constexpr const char* kDefinition = "definition";  // of /fluid/pressure and /fluid/eps_velocity

}  // namespace cgd::schema::names
