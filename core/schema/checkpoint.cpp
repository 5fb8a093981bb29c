// The checkpoint file (checkpoint.h5, docs/schema-run.md "Checkpoint"): writing and the validating read of a
// run's restart state. The names are core/schema/checkpoint.hpp's.
#include "core/schema/checkpoint.hpp"

#include "core/error.hpp"
#include "core/schema/check.hpp"
#include "core/schema/common.hpp"

namespace cgd::checkpoint {

using namespace names;

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
    schema::write_common(file, schema::kCheckpoint, scene);
    file.set_attr(kRoot, kStep, state.step);
    file.set_attr(kRoot, kTime, state.time_s);
    file.set_attr(kRoot, kRebuildDue, static_cast<std::int64_t>(state.rebuild_due));
    file.set_attr(kRoot, kSkin, state.skin_m);
    file.set_attr(kRoot, kLastSortStep, state.last_sort_step);
    file.set_attr(kRoot, kRanks, static_cast<std::int64_t>(ranks));
    file.set_attr(kRoot, kRankParticleCounts, counts);
    file.set_attr(kRoot, kRankContactCounts, contact_counts);
    file.set_attr(kRoot, kWallSeconds, state.wall_seconds);
    file.set_attr(kRoot, kPhaseSeconds, state.phase_seconds);
    file.set_attr(kRoot, kFrameSteps, frame_steps);
    file.set_attr(kRoot, kFrameTimes, frame_times);
    file.set_attr(kRoot, kFrameCounts, frame_counts);
    file.set_attr(kRoot, kPlacementMethod, state.placement_method);
    file.set_attr(kRoot, kNeighborRebuilds, state.neighbor_rebuilds);
    if (!state.slab_bounds.empty()) {  // the engine's always; absent, a restart rebuilds the list at once
      if (static_cast<int>(state.slab_bounds.size()) != ranks)
        throw RunError(path + ": checkpoint: " + std::to_string(state.slab_bounds.size()) + " slab bounds for " +
                       std::to_string(ranks) + " ranks");
      file.set_attr(kRoot, kSlabBounds, state.slab_bounds);
    }
    file.create_group(kParticles);
    file.write_rows(kId, particles.id, n, 1);
    file.write_rows(kPosition, particles.position, n, 3);
    file.write_rows(kVelocity, particles.velocity, n, 3);
    if (particles.angular_velocity)
      file.write_rows(kAngularVelocity, particles.angular_velocity, n, 3);
    file.write_rows(kContactCount, particles.contact_count, n, 1);
    {  // floats, held exactly as doubles
      const std::vector<double> anchor(particles.anchor, particles.anchor + 4 * n);
      file.write_rows(kListAnchor, anchor.data(), n, 4);
    }
    file.create_group(kContacts);
    file.write_rows(kPartner, particles.partner, m, 1);
    file.write_rows(kSpring, particles.spring, m, 3);
    if (fluid) {
      file.create_group(kFluid);
      file.set_attr(kFluid, kDtPrevious, fluid->dt_previous_s);
      file.set_attr(kFluid, kFluidSteps, fluid->steps);
      for (std::size_t k = 0; k < kFluidFieldNames.size(); ++k)
        file.write_rows(std::string(kFluid) + "/" + kFluidFieldNames[k], fluid->fields[k], fluid->cells, 1);
    }
  }, h5::Seal::Yes);  // a restart must never run on damaged bytes (schema::kCheckpoint)
}

namespace {

std::int64_t sum(const std::vector<std::int64_t>& v) {
  std::int64_t s = 0;
  for (auto x : v) s += x;
  return s;
}

}  // namespace

Header read_header(const std::string& path, MPI_Comm comm) {
  const h5::File f = h5::File::open_read(path, comm);
  schema::check_format(f, schema::kCheckpoint);
  Header h;
  h.scene_toml = f.attr_string(kRoot, schema::names::kScene);
  h.scene_name = f.attr_string(schema::names::kParams, schema::names::kSceneName);
  h.ranks = f.attr_int(kRoot, kRanks);
  if (h.ranks < 1)
    throw InputError(path + ": attribute '" + kRanks + "' of '/' is " + std::to_string(h.ranks) + ", expected >= 1");
  return h;
}

Reader::Reader(const std::string& path, MPI_Comm comm) : file_(h5::File::open_read(path, comm)) {
  // Everything below reads metadata every rank sees alike, so every rank throws the same InputError;
  // the values (scan_values) are checked in slices, with one collective verdict.
  const h5::File& f = file_;
  version_ = schema::check_format(f, schema::kCheckpoint);
  auto nonnegative = [&](const char* name, std::int64_t v) {
    if (v < 0)
      throw InputError(path + ": attribute '" + name + "' of '/' is " + std::to_string(v) + ", expected >= 0");
    return v;
  };
  RunState& s = state_;
  s.step = nonnegative(kStep, f.attr_int(kRoot, kStep));
  s.time_s = schema::finite_attr(f, kRoot, kTime);
  // versions 1 and 2 held one displacement bound instead of the anchors: not needed, the restart rebuilds
  s.rebuild_due = f.attr_int(kRoot, kRebuildDue) != 0;
  if (f.has_attr(kRoot, kSkin)) s.skin_m = schema::finite_attr(f, kRoot, kSkin);  // version 1's first files: none
  s.last_sort_step = nonnegative(kLastSortStep, f.attr_int(kRoot, kLastSortStep));
  s.neighbor_rebuilds = nonnegative(kNeighborRebuilds, f.attr_int(kRoot, kNeighborRebuilds));
  s.wall_seconds = schema::finite_attr(f, kRoot, kWallSeconds);
  s.phase_seconds = schema::finite_attrs(f, kRoot, kPhaseSeconds);
  const auto steps = f.attr_ints(kRoot, kFrameSteps);
  const auto times = schema::finite_attrs(f, kRoot, kFrameTimes, steps.size());
  const auto counts = f.attr_ints(kRoot, kFrameCounts);
  if (counts.size() != steps.size())
    throw InputError(path + ": attribute '" + kFrameCounts + "' of '/' holds " + std::to_string(counts.size()) +
                     " values, expected " + std::to_string(steps.size()) + " (one per " + kFrameSteps + ")");
  for (std::size_t k = 0; k < steps.size(); ++k) s.frames.push_back({steps[k], times[k], counts[k]});
  s.placement_method = f.attr_string(kRoot, kPlacementMethod);
  ranks_ = f.attr_int(kRoot, kRanks);
  if (ranks_ < 1) throw InputError(path + ": attribute '" + kRanks + "' of '/' is " + std::to_string(ranks_) + ", expected >= 1");
  particle_counts_ = f.attr_ints(kRoot, kRankParticleCounts);
  contact_counts_ = f.attr_ints(kRoot, kRankContactCounts);
  if (f.has_attr(kRoot, kSlabBounds)) {  // version 4: the DEM slabs in force, one lower bound per rank from 0
    s.slab_bounds = schema::finite_attrs(f, kRoot, kSlabBounds);
    bool valid = static_cast<std::int64_t>(s.slab_bounds.size()) == ranks_ && s.slab_bounds.front() == 0.0;
    for (std::size_t r = 1; valid && r < s.slab_bounds.size(); ++r) valid = s.slab_bounds[r] > s.slab_bounds[r - 1];
    if (!valid)
      throw InputError(path + ": attribute '" + kSlabBounds + "' of '/' holds " + std::to_string(s.slab_bounds.size()) +
                       " values, expected ranks = " + std::to_string(ranks_) + " increasing lower bounds from 0");
  }
  for (const auto* list : {&particle_counts_, &contact_counts_}) {
    const char* name = list == &particle_counts_ ? kRankParticleCounts : kRankContactCounts;
    if (static_cast<std::int64_t>(list->size()) != ranks_)
      throw InputError(path + ": attribute '" + name + "' of '/' holds " + std::to_string(list->size()) +
                       " values, expected ranks = " + std::to_string(ranks_));
    for (auto c : *list)
      if (c < 0) throw InputError(path + ": attribute '" + name + "' of '/' holds " + std::to_string(c) + ", expected >= 0");
  }
  const auto n = static_cast<std::uint64_t>(sum(particle_counts_));
  const auto m = static_cast<std::uint64_t>(sum(contact_counts_));
  const std::string nwhy = "N = " + std::to_string(n) + " particles, the sum of rank_particle_counts";
  const std::string mwhy = "M = " + std::to_string(m) + " contact records, the sum of rank_contact_counts";
  schema::require_shape(f, kId, {n}, nwhy);
  schema::require_shape(f, kPosition, {n, 3}, nwhy);
  schema::require_shape(f, kVelocity, {n, 3}, nwhy);
  if (f.exists(kAngularVelocity)) schema::require_shape(f, kAngularVelocity, {n, 3}, nwhy);
  schema::require_shape(f, kContactCount, {n}, nwhy);
  if (version_ >= 3) schema::require_shape(f, kListAnchor, {n, 4}, nwhy);
  schema::require_shape(f, kPartner, {m}, mwhy);
  schema::require_shape(f, kSpring, {m, 3}, mwhy);
  for (const char* d : {kId, kContactCount, kPartner})
    if (!f.is_integer(d))
      throw InputError(path + ": dataset '" + std::string(d) + "' holds floating-point values, expected integers (int64)");
  if (f.exists(kFluid)) {
    const double dt = schema::finite_attr(f, kFluid, kDtPrevious);
    if (dt < 0) throw InputError(path + ": attribute '" + kDtPrevious + "' of '" + kFluid + "' is negative, expected >= 0");
    nonnegative((std::string(kFluidSteps) + " of " + kFluid).c_str(), f.attr_int(kFluid, kFluidSteps));
    const std::string first = std::string(kFluid) + "/" + kFluidFieldNames[0];
    const auto dims = schema::require_shape(f, first, {schema::kAnyExtent});
    fluid_cells_ = static_cast<std::int64_t>(dims[0]);
    for (const char* name : kFluidFieldNames)
      schema::require_shape(f, std::string(kFluid) + "/" + name, {dims[0]},
                            std::to_string(dims[0]) + " cells, as " + first);
  }
  scan_values(comm, static_cast<std::int64_t>(n), static_cast<std::int64_t>(m));
}

void Reader::scan_values(MPI_Comm comm, std::int64_t n, std::int64_t m) const {
  int rank = 0, ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  const std::string& path = file_.path();
  auto slice = [&](std::int64_t total) {
    return std::pair<std::int64_t, std::int64_t>{total * rank / ranks, total * (rank + 1) / ranks};
  };
  std::string error;
  std::int64_t contacts = 0;
  try {
    const auto [p0, p1] = slice(n);
    for (const char* d : {kPosition, kVelocity, kAngularVelocity}) {
      if (!file_.exists(d)) continue;
      const std::vector<double> v = file_.read_rows_double(d, p0, p1 - p0);
      schema::require_finite(path, d, v.data(), v.size(), 3, static_cast<std::size_t>(p0));
    }
    if (version_ >= 3) {
      const char* d = kListAnchor;
      const std::vector<double> a = file_.read_rows_double(d, p0, p1 - p0);
      schema::require_finite(path, d, a.data(), a.size(), 4, static_cast<std::size_t>(p0));
      for (std::size_t k = 3; k < a.size(); k += 4)
        if (!(a[k] >= 0))
          throw InputError(path + ": dataset '" + std::string(d) + "' holds the reach " + std::to_string(a[k]) +
                           " at row " + std::to_string(p0 + static_cast<std::int64_t>(k / 4)) + ", expected >= 0");
    }
    const std::vector<std::int64_t> id = file_.read_rows_int(kId, p0, p1 - p0);
    for (std::size_t i = 0; i < id.size(); ++i)
      if (id[i] < 0)
        throw InputError(path + ": dataset '" + kId + "' holds " + std::to_string(id[i]) + " at row " +
                         std::to_string(p0 + static_cast<std::int64_t>(i)) + ", expected an id >= 0");
    for (std::int64_t c : file_.read_rows_int(kContactCount, p0, p1 - p0)) {
      if (c < 0)
        throw InputError(path + ": dataset '" + kContactCount + "' holds " + std::to_string(c) + ", expected >= 0");
      contacts += c;
    }
    const auto [c0, c1] = slice(m);
    for (std::int64_t q : file_.read_rows_int(kPartner, c0, c1 - c0))
      if (q < 0)
        throw InputError(path + ": dataset '" + kPartner + "' holds " + std::to_string(q) + ", expected an id >= 0");
    const std::vector<double> spring = file_.read_rows_double(kSpring, c0, c1 - c0);
    schema::require_finite(path, kSpring, spring.data(), spring.size(), 3, static_cast<std::size_t>(c0));
    if (fluid_cells_ > 0) {
      const auto [f0, f1] = slice(fluid_cells_);
      for (const char* name : kFluidFieldNames) {
        const std::string d = std::string(kFluid) + "/" + name;
        const std::vector<double> v = file_.read_rows_double(d, f0, f1 - f0);
        schema::require_finite(path, d, v.data(), v.size(), 1, static_cast<std::size_t>(f0));
      }
    }
  } catch (const std::exception& e) {
    error = e.what();
  }
  schema::throw_if_any(comm, error);
  std::int64_t total = 0;
  MPI_Allreduce(&contacts, &total, 1, MPI_INT64_T, MPI_SUM, comm);
  if (total != m)
    throw InputError(path + ": dataset '" + kContactCount + "' sums to " + std::to_string(total) +
                     ", expected M = " + std::to_string(m) + " (the sum of rank_contact_counts)");
}

bool Reader::has_angular_velocity() const {
  return file_.exists(kAngularVelocity);
}

ParticleData Reader::particles(std::int64_t first, std::int64_t count, std::int64_t contact_first,
                               std::int64_t contact_count, bool rotation) const {
  ParticleData d;
  d.id = file_.read_rows_int(kId, first, count);
  d.position = file_.read_rows_double(kPosition, first, count);
  d.velocity = file_.read_rows_double(kVelocity, first, count);
  if (rotation) d.angular_velocity = file_.read_rows_double(kAngularVelocity, first, count);
  d.contact_count = file_.read_rows_int(kContactCount, first, count);
  d.partner = file_.read_rows_int(kPartner, contact_first, contact_count);
  d.spring = file_.read_rows_double(kSpring, contact_first, contact_count);
  if (version_ >= 3) {
    const std::vector<double> a = file_.read_rows_double(kListAnchor, first, count);
    d.anchor.assign(a.begin(), a.end());  // floats written as doubles: exact
  }
  return d;
}

bool Reader::has_fluid() const {
  return file_.exists(kFluid);
}
double Reader::fluid_dt_previous_s() const {
  return file_.attr_double(kFluid, kDtPrevious);
}
std::int64_t Reader::fluid_steps() const {
  return file_.attr_int(kFluid, kFluidSteps);
}

void Reader::read_fluid_field(std::size_t field, std::int64_t first, std::int64_t count, double* out) const {
  const std::vector<double> data =
      file_.read_rows_double(std::string(kFluid) + "/" + kFluidFieldNames.at(field), first, count);
  std::copy(data.begin(), data.end(), out);
}

void Reader::close() {
  file_.close();
}

}  // namespace cgd::checkpoint
