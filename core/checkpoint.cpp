// checkpoint.h5 (docs/schema-run.md, "Checkpoint"): writing and reading a run's restart state.
#include "core/checkpoint.hpp"

#include "core/output.hpp"

namespace cgd::checkpoint {

void write(const std::string& path, MPI_Comm comm, const Scene& scene, const RunState& state,
           const ParticleRows& particles, const FluidRows* fluid) {
  int ranks = 1;
  MPI_Comm_size(comm, &ranks);
  const std::int64_t n = particles.count, m = particles.contact_rows;
  std::vector<std::int64_t> counts(static_cast<std::size_t>(ranks)),
      contact_counts(static_cast<std::size_t>(ranks));
  MPI_Allgather(&n, 1, MPI_INT64_T, counts.data(), 1, MPI_INT64_T, comm);
  MPI_Allgather(&m, 1, MPI_INT64_T, contact_counts.data(), 1, MPI_INT64_T, comm);
  std::vector<std::int64_t> frame_steps, frame_counts;
  std::vector<double> frame_times;
  for (const Frame& f : state.frames) {
    frame_steps.push_back(f.step);
    frame_times.push_back(f.time_s);
    frame_counts.push_back(f.particle_count);
  }
  h5::write_atomically(path, comm, [&](h5::File& file) {
    schema::write_common(file, "checkpoint", scene);
    file.set_attr("/", "step", state.step);
    file.set_attr("/", "time", state.time_s);
    file.set_attr("/", "displacement_bound", state.displacement_bound_m);
    file.set_attr("/", "rebuild_due", static_cast<std::int64_t>(state.rebuild_due));
    file.set_attr("/", "skin", state.skin_m);
    file.set_attr("/", "last_sort_step", state.last_sort_step);
    file.set_attr("/", "ranks", static_cast<std::int64_t>(ranks));
    file.set_attr("/", "rank_particle_counts", counts);
    file.set_attr("/", "rank_contact_counts", contact_counts);
    file.set_attr("/", "wall_seconds", state.wall_seconds);
    file.set_attr("/", "phase_seconds", state.phase_seconds);
    file.set_attr("/", "frame_steps", frame_steps);
    file.set_attr("/", "frame_times", frame_times);
    file.set_attr("/", "frame_counts", frame_counts);
    file.set_attr("/", "placement_method", state.placement_method);
    file.set_attr("/", "neighbor_rebuilds", state.neighbor_rebuilds);
    file.create_group("/particles");
    file.write_rows("/particles/id", particles.id, n, 1);
    file.write_rows("/particles/position", particles.position, n, 3);
    file.write_rows("/particles/velocity", particles.velocity, n, 3);
    if (particles.angular_velocity)
      file.write_rows("/particles/angular_velocity", particles.angular_velocity, n, 3);
    file.write_rows("/particles/contact_count", particles.contact_count, n, 1);
    file.create_group("/contacts");
    file.write_rows("/contacts/partner", particles.partner, m, 1);
    file.write_rows("/contacts/spring", particles.spring, m, 3);
    if (fluid) {
      file.create_group("/fluid");
      file.set_attr("/fluid", "dt_previous", fluid->dt_previous_s);
      file.set_attr("/fluid", "steps", fluid->steps);
      for (std::size_t k = 0; k < kFluidFieldNames.size(); ++k)
        file.write_rows(std::string("/fluid/") + kFluidFieldNames[k], fluid->fields[k], fluid->cells, 1);
    }
  });
}

Reader::Reader(const std::string& path, MPI_Comm comm) : file_(h5::File::open_read(path, comm)) {
  RunState& s = state_;
  s.step = file_.attr_int("/", "step");
  s.time_s = file_.attr_double("/", "time");
  s.displacement_bound_m = file_.attr_double("/", "displacement_bound");
  s.rebuild_due = file_.attr_int("/", "rebuild_due") != 0;
  if (file_.has_attr("/", "skin")) s.skin_m = file_.attr_double("/", "skin");  // older checkpoints: none
  s.last_sort_step = file_.attr_int("/", "last_sort_step");
  s.neighbor_rebuilds = file_.attr_int("/", "neighbor_rebuilds");
  s.wall_seconds = file_.attr_double("/", "wall_seconds");
  s.phase_seconds = file_.attr_doubles("/", "phase_seconds");
  const auto steps = file_.attr_ints("/", "frame_steps");
  const auto times = file_.attr_doubles("/", "frame_times");
  const auto counts = file_.attr_ints("/", "frame_counts");
  for (std::size_t k = 0; k < steps.size(); ++k) s.frames.push_back({steps[k], times[k], counts[k]});
  s.placement_method = file_.attr_string("/", "placement_method");
  ranks_ = file_.attr_int("/", "ranks");
  particle_counts_ = file_.attr_ints("/", "rank_particle_counts");
  contact_counts_ = file_.attr_ints("/", "rank_contact_counts");
}

bool Reader::has_angular_velocity() const {
  return file_.exists("/particles/angular_velocity");
}

ParticleData Reader::particles(std::int64_t first, std::int64_t count, std::int64_t contact_first,
                               std::int64_t contact_count, bool rotation) const {
  ParticleData d;
  d.id = file_.read_rows_int("/particles/id", first, count);
  d.position = file_.read_rows_double("/particles/position", first, count);
  d.velocity = file_.read_rows_double("/particles/velocity", first, count);
  if (rotation) d.angular_velocity = file_.read_rows_double("/particles/angular_velocity", first, count);
  d.contact_count = file_.read_rows_int("/particles/contact_count", first, count);
  d.partner = file_.read_rows_int("/contacts/partner", contact_first, contact_count);
  d.spring = file_.read_rows_double("/contacts/spring", contact_first, contact_count);
  return d;
}

bool Reader::has_fluid() const {
  return file_.exists("/fluid");
}
double Reader::fluid_dt_previous_s() const {
  return file_.attr_double("/fluid", "dt_previous");
}
std::int64_t Reader::fluid_steps() const {
  return file_.attr_int("/fluid", "steps");
}

void Reader::read_fluid_field(std::size_t field, std::int64_t first, std::int64_t count, double* out) const {
  const std::vector<double> data =
      file_.read_rows_double(std::string("/fluid/") + kFluidFieldNames.at(field), first, count);
  std::copy(data.begin(), data.end(), out);
}

void Reader::close() {
  file_.close();
}

}  // namespace cgd::checkpoint
