// The run's checkpoint.h5 (sim/run_checkpoint.hpp).
#include "sim/run_checkpoint.hpp"

#include <utility>

#include "core/error.hpp"

namespace cgd {

void write_run_checkpoint(const std::string& path, MPI_Comm comm, const Scene& scene, const dem::DemSystem& dem,
                          double dt_s, CoupledStep* coupled, const RunBook& book) {
  const dem::Particles& p = dem.particles();
  const dem::ContactStore store = dem.contact_store();
  const std::int64_t n = static_cast<std::int64_t>(p.n_owned);
  std::vector<std::int64_t> per_particle(static_cast<std::size_t>(n), 0);
  if (store.offset.size() == p.n_owned + 1)
    for (std::int64_t i = 0; i < n; ++i) per_particle[i] = store.offset[i + 1] - store.offset[i];
  checkpoint::RunState state;
  state.step = dem.step_index();
  state.time_s = static_cast<double>(dem.step_index()) * dt_s;
  state.rebuild_due = dem.rebuild_due();
  state.skin_m = dem.skin();
  state.last_sort_step = dem.last_sort_step();
  state.neighbor_rebuilds = dem.rebuilds();
  state.slab_bounds = dem.slab_bounds();
  state.wall_seconds = book.wall_seconds;
  state.phase_seconds = book.phase_seconds;
  state.frames = book.frames;
  state.placement_method = book.placement_method;
  checkpoint::ParticleRows rows;
  rows.count = n;
  rows.id = p.id.data();
  rows.position = p.x.data();  // unwrapped, as in memory
  rows.velocity = p.v.data();  // leapfrog v_{n-1/2}
  rows.angular_velocity = p.rotation ? p.w.data() : nullptr;
  rows.contact_count = per_particle.data();
  rows.contact_rows = static_cast<std::int64_t>(store.partner.size());
  rows.partner = store.partner.data();
  rows.spring = store.xi.data();
  rows.anchor = dem.anchors().data();  // 4 per owned particle (zero reach before the first build)
  checkpoint::FluidRows fluid_rows;
  if (coupled) fluid_rows = coupled->checkpoint_rows();
  checkpoint::write(path, comm, scene, state, rows, coupled ? &fluid_rows : nullptr);
}

RestoredRun load_run_checkpoint(const std::string& path, MPI_Comm comm, const Scene& scene, dem::DemSystem& dem,
                                double dt_s, std::int64_t end_step, CoupledStep* coupled) {
  int rank = 0, ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  checkpoint::Reader file(path, comm);
  const checkpoint::RunState& state = file.state();
  const std::int64_t step = state.step;
  if (step > end_step)
    throw InputError(scene.source_path + ": run.end_time = " + std::to_string(scene.run.end_time_s) +
                     " s is before the checkpoint's time " + std::to_string(static_cast<double>(step) * dt_s) +
                     " s (" + path + "): a restart can only continue a run; give an end time at or after it");
  const std::vector<std::int64_t>& counts = file.rank_particle_counts();
  const std::vector<std::int64_t>& ccounts = file.rank_contact_counts();
  const bool rotation = dem.particles().rotation;
  if (rotation != file.has_angular_velocity())
    throw InputError(path + ": the checkpoint was written with friction " +
                     std::string(rotation ? "off" : "on") + ", the scene now has it " + (rotation ? "on" : "off"));
  std::int64_t total = 0, total_c = 0;
  for (auto c : counts) total += c;
  for (auto c : ccounts) total_c += c;
  if (total != scene.derived.particle_count)
    throw InputError(path + ": holds " + std::to_string(total) + " particles, the scene calls for " +
                     std::to_string(scene.derived.particle_count) + " (the scene changed since the checkpoint)");
  std::int64_t first = 0, count = total, cfirst = 0, ccount = total_c;
  const bool same_layout = file.ranks() == ranks;
  // the slabs in force at the checkpoint (the DEM's move at every rebuild); without them (a checkpoint older than
  // version 4) each rank still takes its own rows, and the first step rebuilds, which migrates them
  const bool same_slabs = same_layout && !state.slab_bounds.empty();
  if (same_slabs) dem.set_slab_bounds(state.slab_bounds);
  if (same_layout) {
    first = cfirst = 0;
    for (int r = 0; r < rank; ++r) {
      first += counts[r];
      cfirst += ccounts[r];
    }
    count = counts[rank];
    ccount = ccounts[rank];
  }
  checkpoint::ParticleData d = file.particles(first, count, cfirst, ccount, rotation);
  dem::ContactStore store;
  store.offset.assign(1, 0);
  if (same_layout) {
    for (std::int64_t i = 0; i < count; ++i) store.offset.push_back(store.offset.back() + d.contact_count[i]);
    store.partner = std::move(d.partner);
    store.xi = std::move(d.spring);
  } else {
    // Different rank count: keep the particles this rank owns (by wrapped height).
    std::vector<std::int64_t> kid;
    std::vector<double> kx, kv, kw;
    d.anchor.clear();  // another layout rebuilds at once (below): the anchors are not needed
    std::int64_t c0 = 0;
    for (std::int64_t i = 0; i < count; ++i) {
      double q[3] = {d.position[3 * i], d.position[3 * i + 1], d.position[3 * i + 2]};
      dem.slabs().wrap(q);
      const std::int64_t c1 = c0 + d.contact_count[i];
      if (dem.slabs().owner(q[1]) == rank) {
        kid.push_back(d.id[i]);
        kx.insert(kx.end(), q, q + 3);
        kv.insert(kv.end(), &d.velocity[3 * i], &d.velocity[3 * i + 3]);
        if (rotation) kw.insert(kw.end(), &d.angular_velocity[3 * i], &d.angular_velocity[3 * i + 3]);
        for (std::int64_t k = c0; k < c1; ++k) {
          store.partner.push_back(d.partner[k]);
          store.xi.insert(store.xi.end(), &d.spring[3 * k], &d.spring[3 * k + 3]);
        }
        store.offset.push_back(static_cast<std::int64_t>(store.partner.size()));
      }
      c0 = c1;
    }
    d.id = std::move(kid);
    d.position = std::move(kx);
    d.velocity = std::move(kv);
    d.angular_velocity = std::move(kw);
  }
  dem.set_particles(std::move(d.id), std::move(d.position), std::move(d.velocity), std::move(d.angular_velocity));
  if (state.skin_m > 0) dem.set_skin(state.skin_m);  // the anchors' reaches are within half the build's skin
  // no anchors (a checkpoint older than version 3), no slab bounds (older than version 4) or another layout:
  // rebuild at the first step
  dem.restore(std::move(store), std::move(d.anchor), !same_slabs || state.rebuild_due, step, state.last_sort_step);
  dem.set_rebuilds(state.neighbor_rebuilds);
  RestoredRun out;
  out.step = step;
  out.book.wall_seconds = state.wall_seconds;
  out.book.phase_seconds = state.phase_seconds;
  out.book.frames = state.frames;
  out.book.placement_method = state.placement_method;
  if (coupled) coupled->restore(file);
  file.close();
  return out;
}

}  // namespace cgd
