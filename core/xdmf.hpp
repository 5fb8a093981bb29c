#pragma once
// run.xmf of a run directory (XDMF 3, docs/schema-run.md "run.xmf"): the ParaView entry point over the
// snapshots, written by core/xdmf.cpp; the datasets it refers to are named in core/schema/snapshot.hpp.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/scene.hpp"  // Vec3

namespace cgd::schema {

/// One entry of run.xmf's temporal collection.
struct XdmfFrame {
  std::string snapshot_file;  // relative to the run directory, e.g. "snapshots/snap_000000100.h5"
  double time_s = 0;
  std::int64_t particle_count = 0;
  bool has_angular_velocity = false;
  bool has_fluid = false;
  std::array<int, 3> cells{};  // (n_x, n_y, n_z) when has_fluid
  Vec3 spacing_m{}, origin_m{};
};

/// (Re)write `run_dir/run.xmf` (XDMF 3) atomically: a temporal collection whose frames hold the
/// particles as a polyvertex grid with velocity, diameter, id (and angular velocity) and, when
/// present, the fluid as a 3D CoRectMesh with cell data (void_fraction, velocity, pressure).
/// Rank 0 only (not collective).
void write_xdmf(const std::string& run_dir, const std::vector<XdmfFrame>& frames);

}  // namespace cgd::schema
