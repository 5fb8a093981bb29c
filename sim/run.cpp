#include "sim/run.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <iostream>
#include <numbers>
#include <sstream>

#include "core/schema/checkpoint.hpp"
#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/schema/series.hpp"
#include "core/schema/snapshot.hpp"
#include "core/xdmf.hpp"
#include "core/schema/series.hpp"
#include "core/text_file.hpp"
#include "core/timers.hpp"
#include "sim/coupled_step.hpp"
#include "sim/dem/placement.hpp"
#include "sim/progress.hpp"
#include "sim/run_checkpoint.hpp"
#include "sim/run_report.hpp"
#include "sim/fluid/grid.hpp"

namespace fs = std::filesystem;

namespace cgd {

namespace {

/// The signal (SIGINT or SIGTERM) that asked the run to stop, 0 if none: the loop checkpoints at its next
/// step boundary and ends with Interrupted (exit status 128 + signal).
volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void on_signal(int signal_number) { g_interrupted = signal_number; }

std::string snapshot_name(std::int64_t step) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "snap_%09lld.h5", static_cast<long long>(step));
  return buf;
}


/// The peak resident set size of this process so far (getrusage), summed over the ranks. Collective.
double peak_memory_bytes(MPI_Comm comm) {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  double bytes = 1024.0 * static_cast<double>(usage.ru_maxrss);  // Linux: kilobytes
  MPI_Allreduce(MPI_IN_PLACE, &bytes, 1, MPI_DOUBLE, MPI_SUM, comm);
  return bytes;
}

/// The resident set size of this process now (/proc/self/statm), summed over the ranks; 0 where it cannot
/// be read. Collective.
double resident_memory_bytes(MPI_Comm comm) {
  double bytes = 0;
  std::ifstream statm("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  if (statm >> pages_total >> pages_resident) bytes = static_cast<double>(pages_resident) * static_cast<double>(sysconf(_SC_PAGESIZE));
  MPI_Allreduce(MPI_IN_PLACE, &bytes, 1, MPI_DOUBLE, MPI_SUM, comm);
  return bytes;
}

/// A file operation rank 0 does alone, its failure thrown as RunError on every rank (so that no rank is
/// left waiting in its next collective call). Collective.
template <class F>
void on_rank0(MPI_Comm comm, F&& op) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  std::string error;
  if (rank == 0) {
    try {
      op();
    } catch (const std::exception& e) {
      error = std::string(e.what()).empty() ? "file operation failed" : e.what();
    }
  }
  int length = static_cast<int>(error.size());
  MPI_Bcast(&length, 1, MPI_INT, 0, comm);
  error.resize(static_cast<std::size_t>(length));
  MPI_Bcast(error.data(), length, MPI_CHAR, 0, comm);
  if (!error.empty()) throw RunError(error + " (on rank 0)");
}

}  // namespace

dem::DemSettings dem_settings_from_scene(const Scene& scene) {
  const DerivedScales& d = scene.derived;
  dem::DemSettings s;
  s.box_m = scene.domain.size_m;
  s.diameter_m = d.parcel_diameter_m;
  s.mass_kg = d.parcel_mass_kg;
  s.dt_s = d.dt_dem_s;
  s.contacts = scene.has_contacts();
  s.friction = scene.has_friction();
  s.contact.k_n = d.k_n_N_m;
  s.contact.k_t = d.k_t_N_m;
  s.contact.gamma_n = d.gamma_n_kg_s;
  s.contact.gamma_t = d.gamma_t_kg_s;
  s.contact.friction = scene.contact.friction;
  s.contact.dt = d.dt_dem_s;
  if (scene.contact.skin_over_dp) {
    s.skin_m = *scene.contact.skin_over_dp * d.parcel_diameter_m;
  } else {  // adaptive (sim/dem/system.hpp DemSettings)
    s.skin_target_steps = scene.numerics.skin_target_steps;
    s.skin_min_m = ContactConfig::kAdaptiveSkinMin * d.parcel_diameter_m;
    s.skin_max_m = ContactConfig::kAdaptiveSkinMax * d.parcel_diameter_m;
    s.skin_m = s.skin_min_m;
  }
  s.overlap_limit = scene.numerics.overlap_limit;
  s.sort_interval_steps = scene.numerics.sort_interval_steps;
  // the slabs follow the particles (issue 25): the coupler's grid is whole on every rank (coupler.hpp), so they
  // need not match the fluid's FFTW rows
  s.balance_slabs = true;
  const Vec3& g = scene.domain.gravity_m_s2;
  s.drive.accel = {g[0], g[1], g[2]};
  if (scene.fluid && scene.solves_fluid()) {
    // the fluid forces arrive per particle from the coupling (sim/coupling/coupler.hpp)
    s.per_particle_drive = true;
  } else if (scene.fluid) {
    const FluidConfig& f = *scene.fluid;
    if (f.drag != DragLaw::Stokes)
      throw InputError(scene.source_path + ": fluid.drag = \"" + to_string(f.drag) +
                       "\" with coupling = \"quiescent\": only \"stokes\" is available for a fluid at rest in this "
                       "build");
    // Fluid at rest: hydrostatic pressure gradient rho_f g gives buoyancy -V_p rho_f g when the
    // pressure-gradient force is on; Stokes drag per primary 3 pi mu d_p (u - v) with u = 0, times
    // alpha^3 primaries per parcel, over the parcel mass alpha^3 m_p.
    if (f.pressure_gradient_force) {
      const double factor = 1.0 - f.density_kg_m3 / scene.particles.density_kg_m3;
      s.drive.accel = factor * s.drive.accel;
    }
    s.drive.drag_rate =
        StokesDrag(f.density_kg_m3, f.viscosity_Pa_s, scene.particles.diameter_m).force_per_slip() / d.particle_mass_kg;
    if (s.drive.drag_rate * s.dt_s > 0.5)
      throw InputError(scene.source_path + ": the time step " + std::to_string(s.dt_s) +
                       " s is too large for the Stokes relaxation time " + std::to_string(1.0 / s.drive.drag_rate) +
                       " s (explicit drag needs dt < 0.5 tau_p); lower contact.t_star or run.dt");
  }
  return s;
}

namespace {

/// The fluid grid of a scene that solves the fluid (nullptr otherwise). Throws InputError when the
/// grid cannot be split over the ranks. Collective.
std::unique_ptr<fluid::FluidGrid> make_grid(const Scene& scene, MPI_Comm comm) {
  if (!scene.solves_fluid()) return nullptr;
  return std::make_unique<fluid::FluidGrid>(comm, scene.derived.cells, scene.domain.size_m);
}

class RunDriver {
 public:
  RunDriver(const Scene& scene, const RunSettings& settings, MPI_Comm comm)
      : scene_(scene),
        settings_(settings),
        comm_(comm),
        grid_(make_grid(scene, comm)),
        dem_(dem_settings_from_scene(scene), comm),
        progress_(Progress::Settings{}) {
    MPI_Comm_rank(comm_, &rank_);
    MPI_Comm_size(comm_, &ranks_);
    dir_ = settings_.output_dir;
    dt_ = dem_.settings().dt_s;
    end_step_ = std::llround(scene_.run.end_time_s / dt_);
    dump_every_ = scene_.run.dump_interval_s > 0 ? std::max<std::int64_t>(1, std::llround(scene_.run.dump_interval_s / dt_)) : 0;
    series_every_ = scene_.run.series_interval_s > 0
                        ? std::max<std::int64_t>(1, std::llround(scene_.run.series_interval_s / dt_))
                        // default: about 1000 rows, and at least 100 DEM steps apart, so that the diagnostics
                        // (O(N) and a reduction, about one DEM step's work) cost under ~1 % of a run
                        : std::max<std::int64_t>(100, end_step_ / 1000);
    t_output_ = run_timers_.add("output");
    t_checkpoint_ = run_timers_.add("checkpoint");
    t_diag_ = run_timers_.add("diagnostics");
    if (grid_) {
      coupled_ = std::make_unique<CoupledStep>(scene_, *grid_, dt_, run_timers_);
      end_step_ = coupled_end_step(end_step_, dump_every_, scene_.run.end_time_s, scene_.run.dump_interval_s);
    }
    Progress::Settings ps;
    ps.tool = settings_.tool;
    ps.mode = Progress::mode_for(settings_.quiet);
    ps.interval_s = settings_.progress_interval_s;
    ps.end_step = end_step_;
    ps.dt_s = dt_;
    ps.t_ref_s = scene_.derived.t_ref_s;
    ps.fluid_scene = scene_.fluid.has_value();
    ps.solves_fluid = coupled_ != nullptr;
    progress_ = Progress(ps);
  }

  /// Coupled runs whose end time is a whole number k of snapshot intervals end on the k-th snapshot step.
  /// Rounding both times to DEM steps separately can leave the end up to k/2 DEM steps past the last
  /// snapshot: a final fluid step of a few DEM steps, whose continuity source -- the eps change of the whole
  /// previous fluid step (deposited at the step's start, coupler.hpp) over its own short dt -- spoils the
  /// final snapshot's fluid fields (measured: a pressure gradient of 1.9e4 Pa/m and 0.37 m/s at the
  /// particles after a one-DEM-step final step). The end moves by at most k/2 DEM steps.
  static std::int64_t coupled_end_step(std::int64_t end_step, std::int64_t dump_every, double end_s, double dump_s) {
    if (dump_every <= 0 || !(dump_s > 0)) return end_step;
    const double k = std::round(end_s / dump_s);
    if (k >= 1 && std::abs(end_s / dump_s - k) < 1e-6 * k) return static_cast<std::int64_t>(k) * dump_every;
    return end_step;
  }

  void run() {
    check_directory();
    // Placement and the checkpoint can still refuse the scene (InputError): both before anything is written.
    if (!settings_.restart) initial_state();
    else load_checkpoint();
    if (settings_.restart && restarted_from_ == end_step_) {
      int done = rank_ == 0 && fs::exists(dir_ / "DONE") ? 1 : 0;
      MPI_Bcast(&done, 1, MPI_INT, 0, comm_);
      if (done) {  // nothing to run: leave the completed run as it is
        if (rank_ == 0)
          std::cout << settings_.tool << ": " << dir_.string() << " is already complete at step " << end_step_
                    << " (t = " << static_cast<double>(end_step_) * dt_
                    << " s); nothing to do (raise run.end_time to continue it)\n"
                    << std::flush;
        return;
      }
    }
    on_rank0(comm_, [&] {
      fs::create_directories(dir_ / "snapshots");
      write_text_atomically(dir_ / "scene.toml", scene_.effective_toml);
    });
    // Test hook of the one-rank-error handling (tests/e2e/rank_errors.sh): an error on one rank only.
    if (const char* r = std::getenv("CGD_TEST_FAIL_ON_RANK"); r && std::atoi(r) == rank_)
      throw RunError("failure injected on rank " + std::to_string(rank_) + " (CGD_TEST_FAIL_ON_RANK)");
    MPI_Barrier(comm_);
    estimate_memory();
    print_banner();
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    time_loop();
    finish();
  }

 private:
  void check_directory() {
    // Collective decision on rank 0's view of the file system; nothing is written before it.
    int status = 0;
    if (rank_ == 0) {
      if (settings_.restart) {
        if (!fs::exists(dir_ / "checkpoint.h5")) status = 1;
      } else if (fs::exists(dir_) && !fs::is_empty(dir_)) {
        status = 2;
      }
    }
    MPI_Bcast(&status, 1, MPI_INT, 0, comm_);
    if (status == 1)
      throw InputError((dir_ / "checkpoint.h5").string() + ": no checkpoint to restart from (--restart needs a run " +
                       "directory written by an earlier run of this scene)");
    if (status == 2)
      throw InputError(dir_.string() + ": the output directory already holds files; continue that run with " +
                       "--restart, or remove it / choose another with -o");
  }

  void initial_state() {
    // Distributed and the same for any rank count (placement.hpp); the first rebuild migrates each
    // particle to the rank that owns its slab (the slabs balanced first).
    dem::LocalPlacement placement;
    const double t0 = wall_seconds();
    try {
      placement = dem::place_particles_distributed(comm_, scene_.domain.size_m, dem_.settings().diameter_m,
                                                   scene_.derived.particle_count, scene_.particles.velocity_rms_m_s,
                                                   scene_.particles.seed);
    } catch (const InputError& e) {
      throw InputError(scene_.source_path + ": particles.solids_fraction = " +
                       std::to_string(scene_.particles.solids_fraction) + ": " + e.what());
    }
    placement_seconds_ = wall_seconds() - t0;
    placement_method_ = placement.method;
    placement_gap_ = placement.min_gap_rel;
    dem_.set_particles(std::move(placement.id), std::move(placement.position), std::move(placement.velocity), {});
    declare_series();
  }

  /// The series columns of this run: fixed by the scene and the phase timers (restarts included).
  schema::RunSeriesLayout series_layout() const {
    return {scene_.fluid.has_value(), coupled_ != nullptr, phase_names()};
  }

  void declare_series() {
    series_ = schema::Series();
    schema::declare_run_columns(series_, series_layout());
  }

  std::vector<std::string> phase_names() const {
    std::vector<std::string> names = dem_.timers().names();
    for (const std::string& n : run_timers_.names()) names.push_back(n);
    for (std::string& n : names) {  // dataset names: "force+integrate" -> force_integrate, "fluid pressure" -> fluid_pressure
      std::replace(n.begin(), n.end(), '+', '_');
      std::replace(n.begin(), n.end(), ' ', '_');
    }
    return names;
  }
  std::vector<double> phase_seconds() const {
    std::vector<double> s = dem_.timers().all_seconds();
    for (double v : run_timers_.all_seconds()) s.push_back(v);
    return s;
  }

  double elapsed() const { return wall_offset_ + (wall_seconds() - wall_start_); }

  void append_series_row(std::int64_t step) {
    ScopedPhase t(run_timers_, t_diag_);
    // dry runs: between advance and commit (synchronous velocities); coupled: at a fluid-step boundary
    const dem::Diagnostics d = dem_.diagnostics(!coupled_);
    fluid::FlowAverages avg;
    if (coupled_) avg = coupled_->fluid().averages();
    const double volume = scene_.domain.size_m[0] * scene_.domain.size_m[1] * scene_.domain.size_m[2];
    schema::RunSeriesRow r;
    r.time_s = static_cast<double>(step) * dt_;
    r.step = step;
    r.solids_fraction = static_cast<double>(d.particles) * scene_.derived.parcel_volume_factor *
                        scene_.derived.particle_volume_m3 / volume;
    // slip = <eps u>/<eps> - <phi v>/<phi> (docs/models.md); a quiescent fluid has u = 0
    for (int c = 0; c < 3; ++c) r.slip_velocity_m_s[c] = avg.fluid_velocity[c] - d.velocity_mean[c];
    r.fluid_velocity_mean_m_s = avg.fluid_velocity;
    r.particle_velocity_mean_m_s = d.velocity_mean;
    r.kinetic_energy_J = d.kinetic_translational_J;
    r.rotational_energy_J = d.kinetic_rotational_J;
    r.contact_energy_J = d.contact_energy_J;
    r.momentum_kg_m_s = d.momentum;
    r.contacts_per_particle = d.particles > 0 ? 2.0 * d.contacts / static_cast<double>(d.particles) : 0.0;
    r.max_overlap_rel = d.max_overlap_rel;
    r.neighbor_rebuilds = dem_.rebuilds();
    r.wall_seconds = elapsed();
    MPI_Bcast(&r.wall_seconds, 1, MPI_DOUBLE, 0, comm_);  // identical rows on every rank
    if (coupled_) {
      const fluid::StepReport& report = coupled_->fluid().last_report();
      r.dt_fluid_s = report.dt_s;
      r.fluid_kinetic_energy_J = avg.kinetic_energy_J;
      r.continuity_residual_rel = report.continuity_relative;
      r.pressure_iterations = report.pressure.iterations;
      r.max_solids_fraction = coupled_->coupler().max_solids_fraction();
      r.floored_cells = coupled_->coupler().floored_cells();
    }
    r.phase_seconds = phase_seconds();
    MPI_Bcast(r.phase_seconds.data(), static_cast<int>(r.phase_seconds.size()), MPI_DOUBLE, 0, comm_);
    schema::append_run_row(series_, series_layout(), r);
    const double u_t = scene_.derived.u_t_m_s;
    progress_physics_ = {u_t > 0 ? r.slip_velocity_m_s[1] / u_t : 0.0, r.kinetic_energy_J, r.max_overlap_rel,
                         r.max_solids_fraction, r.dt_fluid_s};
  }

  /// Snapshot of step n, between advance() and commit(): x_n and the synchronous velocities.
  void write_snapshot(std::int64_t step, const std::string& name, bool add_frame) {
    ScopedPhase t(run_timers_, t_output_);
    const dem::Particles& p = dem_.particles();
    std::vector<double> x(p.x.begin(), p.x.begin() + 3 * static_cast<std::ptrdiff_t>(p.n_owned));
    for (std::size_t i = 0; i < p.n_owned; ++i) dem_.slabs().wrap(&x[3 * i]);
    // dry: synchronous v_n between advance and commit; coupled: at a fluid-step boundary, the
    // leapfrog velocity v_{n-1/2} (the one the drag used), O(dt_DEM) from v_n
    const std::vector<double> v = coupled_ ? std::vector<double>(p.v.begin(), p.v.begin() + 3 * static_cast<std::ptrdiff_t>(p.n_owned))
                                         : dem_.synchronous_velocity();
    const std::vector<double> w = coupled_ ? (p.rotation ? std::vector<double>(p.w.begin(), p.w.begin() + 3 * static_cast<std::ptrdiff_t>(p.n_owned))
                                                      : std::vector<double>{})
                                         : dem_.synchronous_angular_velocity();
    const std::vector<double> diameter(p.n_owned, dem_.settings().diameter_m);
    schema::ParticleFields f;
    f.count = static_cast<std::int64_t>(p.n_owned);
    f.id = p.id.data();
    f.position = x.data();
    f.velocity = v.data();
    f.angular_velocity = p.rotation ? w.data() : nullptr;
    f.diameter = diameter.data();
    schema::FluidFields ff;
    fluid::FileOrderFields fo;
    if (coupled_) {
      const coupling::ParticleCoupling& pc = coupled_->coupler().particles();
      f.drag_coefficient = pc.beta.data();
      f.fluid_velocity = pc.fluid_velocity.data();
      f.pressure_gradient = pc.pressure_gradient.data();
      f.pressure_gradient_mean = coupled_->pressure_gradient_mean();
      coupled_->fluid().fill_file_order(fo);
      ff.cells = grid_->cells();
      ff.spacing_m = grid_->spacing();
      ff.origin_m = {0.0, 0.0, 0.0};
      ff.y_offset = grid_->j0();
      ff.y_count = grid_->ny_local();
      ff.void_fraction = fo.void_fraction.data();
      ff.velocity = fo.velocity.data();
      ff.pressure = fo.pressure.data();
      ff.eps_velocity = fo.eps_velocity.data();
    }
    schema::write_snapshot((dir_ / "snapshots" / name).string(), comm_, scene_, static_cast<double>(step) * dt_, step,
                           f, coupled_ ? &ff : nullptr);
    if (add_frame) {
      std::int64_t n = f.count;
      MPI_Allreduce(MPI_IN_PLACE, &n, 1, MPI_INT64_T, MPI_SUM, comm_);
      frames_.push_back({step, static_cast<double>(step) * dt_, n});
      on_rank0(comm_, [&] { schema::write_xdmf(dir_.string(), xdmf_frames()); });
    }
  }

  std::vector<schema::XdmfFrame> xdmf_frames() const {
    std::vector<schema::XdmfFrame> out;
    for (const checkpoint::Frame& fr : frames_) {
      schema::XdmfFrame x;
      x.snapshot_file = "snapshots/" + snapshot_name(fr.step);
      x.time_s = fr.time_s;
      x.particle_count = fr.particle_count;
      x.has_angular_velocity = dem_.particles().rotation;
      if (grid_) {
        x.has_fluid = true;
        x.cells = grid_->cells();
        x.spacing_m = grid_->spacing();
        x.origin_m = {0.0, 0.0, 0.0};
      }
      out.push_back(x);
    }
    return out;
  }

  void write_series() {
    ScopedPhase t(run_timers_, t_output_);
    series_.write((dir_ / "series.h5").string(), comm_, scene_);
  }

  // ---- checkpoint (sim/run_checkpoint.hpp; layout: core/schema/checkpoint.hpp) --------------------------
  /// The run's book-keeping as the checkpoint keeps it, the same on every rank (rank 0's clock). Collective.
  RunBook book() const {
    RunBook b;
    b.wall_seconds = elapsed();
    MPI_Bcast(&b.wall_seconds, 1, MPI_DOUBLE, 0, comm_);
    b.phase_seconds = phase_seconds();
    MPI_Bcast(b.phase_seconds.data(), static_cast<int>(b.phase_seconds.size()), MPI_DOUBLE, 0, comm_);
    b.frames = frames_;
    b.placement_method = placement_method_;
    return b;
  }

  void write_checkpoint() {
    ScopedPhase t(run_timers_, t_checkpoint_);
    const RunBook b = book();
    // The series first: a kill between the two leaves a series that reaches past the older checkpoint
    // (a restart cuts it back), never one that stops short of the newer checkpoint (a gap of rows).
    write_series();
    write_run_checkpoint((dir_ / "checkpoint.h5").string(), comm_, scene_, dem_, dt_, coupled_.get(), b);
    last_checkpoint_wall_ = wall_seconds();
  }

  void load_checkpoint() {
    const RestoredRun r = load_run_checkpoint((dir_ / "checkpoint.h5").string(), comm_, scene_, dem_, dt_, end_step_,
                                              coupled_.get());
    wall_offset_ = r.book.wall_seconds;
    const std::vector<double>& phases = r.book.phase_seconds;
    const std::size_t nd = dem_.timers().names().size();
    dem_.timers().set_all_seconds(std::vector<double>(phases.begin(), phases.begin() + std::min(nd, phases.size())));
    if (phases.size() > nd) run_timers_.set_all_seconds(std::vector<double>(phases.begin() + nd, phases.end()));
    frames_ = r.book.frames;
    placement_method_ = r.book.placement_method;
    const fs::path series_path = dir_ / "series.h5";
    if (fs::exists(series_path)) {
      series_ = schema::Series::read(series_path.string(), comm_);
      series_.truncate_after((static_cast<double>(r.step) - 0.5) * dt_);
      overlap_warned_ = !series_.warnings().empty();  // warned once per run, restarts included
    } else {
      declare_series();
    }
    restarted_from_ = r.step;
  }

  // ---- loop ---------------------------------------------------------------------------------------
  /// The peak memory of the run (all ranks), estimated before the loop: what is resident after setup
  /// (libraries, MPI and FFTW buffers, particles, placement or checkpoint reading, the fluid grid and its
  /// solver) plus what the loop still allocates: per rank, the HDF5 / MPI-IO buffers of the first file
  /// written; per particle, the neighbour list with its history slots, ghosts, the force arrays
  /// and the snapshot copies (and in coupled runs the coupling's per-particle fields); per cell, the
  /// snapshot's file-order fields. The growth coefficients are measured (peak resident set minus the
  /// resident set here, 3k-200k particles, dry and coupled, 1 and 2 ranks): the estimate came within 7 %
  /// of the measured peak in every case. They were measured with the second state buffer that the in-place
  /// integration (issue 17) removed (about 24-48 B per particle): the estimate is now a little high. Collective.
  void estimate_memory() {
    constexpr double kPerRank = 5.0 * kMiB;
    const double per_particle = coupled_ ? 250.0 : 60.0;  // bytes
    constexpr double kPerCell = 70.0;                     // bytes
    resident_at_start_ = resident_memory_bytes(comm_);
    const double cells = grid_ ? static_cast<double>(grid_->cells()[0]) * grid_->cells()[1] * grid_->cells()[2] : 0.0;
    memory_estimate_bytes_ = resident_at_start_ + kPerRank * ranks_ +
                             per_particle * static_cast<double>(scene_.derived.particle_count) + kPerCell * cells;
  }

  /// What the run is and will do (stdout, rank 0, not with --quiet): sim/run_report.hpp's banner.
  void print_banner() {
    if (settings_.quiet) return;
    // Collective: the fluid's current step limit (u = 0 at a fresh start).
    const double fluid_limit_now = coupled_ ? coupled_->max_fluid_dt() : 0.0;
    if (rank_ != 0) return;
    RunBanner b;
    b.tool = settings_.tool;
    b.scene = &scene_;
    b.memory_estimate_bytes = memory_estimate_bytes_;
    b.resident_at_start_bytes = resident_at_start_;
    b.ranks = ranks_;
    b.restarted_from = restarted_from_;
    b.placement_method = placement_method_;
    b.placement_gap = placement_gap_;
    b.placement_seconds = placement_seconds_;
    b.end_step = end_step_;
    b.dump_every = dump_every_;
    b.series_every = series_every_;
    b.dt_s = dt_;
    b.coupled = coupled_ != nullptr;
    if (coupled_) {
      b.drag_dt_cap_s = coupled_->drag_dt_cap();
      b.viscous_dt_limit_s = coupled_->fluid().viscous_dt_limit();
      b.fluid_limit_now_s = fluid_limit_now;
    }
    b.output_dir = dir_.string();
    std::cout << run_banner(b) << std::flush;
  }

  /// A progress line when due (rank 0; sim/progress.hpp), with the physics of the latest series row.
  void progress(std::int64_t step, bool force) {
    if (rank_ == 0) progress_.update(step, progress_physics_, force);
  }

  void time_loop() {
    if (coupled_) return time_loop_coupled();
    begin_loop();
    for (;;) {
      const std::int64_t step = dem_.step_index();
      // every 16 steps (and at the end): agree on checkpoint and interruption; one collective call
      if (step % 16 == 0 || step == end_step_) checkpoint_if_due(step);
      dem_.prepare();
      dem_.advance();
      const bool final_step = step >= end_step_;
      if (step % series_every_ == 0 || final_step) append_series_row(step);
      snapshot_if_due(step, final_step);
      if (final_step) break;
      or_diagnose([&] { dem_.commit(); });
      warn_if_overlap_high();
      progress(dem_.step_index(), false);
    }
    progress(end_step_, true);
  }

  void begin_loop() {
    loop_start_wall_ = wall_seconds();
    last_checkpoint_wall_ = loop_start_wall_;
    loop_start_step_ = dem_.step_index();
    session_start_phases_ = phase_seconds();
    if (rank_ == 0) progress_.begin(loop_start_step_);
  }

  /// A snapshot at step 0, every dump interval and the end, with the series rewritten beside it.
  void snapshot_if_due(std::int64_t step, bool final_step) {
    if (!(final_step || step == 0 || (dump_every_ > 0 && step % dump_every_ == 0))) return;
    write_snapshot(step, snapshot_name(step), true);
    write_series();
  }

  /// A failed run keeps its last good checkpoint and leaves the failed state for diagnosis.
  template <class F>
  void or_diagnose(F&& body) {
    try {
      body();
    } catch (const RunError&) {
      diagnostic_snapshot();
      write_series();
      throw;
    }
  }

  /// Checkpoint and interruption agreement at a step boundary (shared by both loops).
  void checkpoint_if_due(std::int64_t step) {
    if (step == end_step_ && restarted_from_ != step) write_checkpoint();  // the final state can be extended
    if (step == end_step_) return;
    int flags[2] = {static_cast<int>(g_interrupted), 0};  // the signal (max over ranks), checkpoint due
    if (rank_ == 0 && wall_seconds() - last_checkpoint_wall_ >= scene_.run.checkpoint_wall_s) flags[1] = 1;
    MPI_Allreduce(MPI_IN_PLACE, flags, 2, MPI_INT, MPI_MAX, comm_);
    if (flags[0]) {
      write_checkpoint();
      progress(step, true);
      throw Interrupted(std::string(flags[0] == SIGINT ? "SIGINT" : flags[0] == SIGTERM ? "SIGTERM" : "a signal") +
                            " at step " + std::to_string(step) + " (t = " +
                            std::to_string(static_cast<double>(step) * dt_) + " s); checkpoint written to " +
                            (dir_ / "checkpoint.h5").string() + ", continue with --restart",
                        flags[0]);
    }
    if ((flags[1] || checkpoint_requested_) && step != restarted_from_) write_checkpoint();
    checkpoint_requested_ = false;
  }

  /// Once per run, when the largest overlap (global, DemSystem::commit) passes numerics.
  /// overlap_warning_fraction of numerics.overlap_limit: say so on stderr and in the series, with the
  /// contact stiffness that would keep it below, and checkpoint at the next chance (a state before the
  /// likely failure). The peak overlap of an impact at speed v is v sqrt(m_eff/k_n), so it scales as
  /// k_n^(-1/2), i.e. linearly with gamma* (docs/models.md: k_n ~ gamma*^-2).
  void warn_if_overlap_high() {
    if (overlap_warned_) return;
    const NumericsConfig& nm = scene_.numerics;
    const double overlap = dem_.last_max_overlap_rel();
    const double threshold = nm.overlap_warning_fraction * nm.overlap_limit;
    if (!(overlap > threshold)) return;
    overlap_warned_ = true;
    checkpoint_requested_ = true;
    const std::int64_t step = dem_.step_index();
    std::ostringstream o;
    o.precision(3);
    o << "warning at step " << step << " (t = " << static_cast<double>(step) * dt_ << " s): the largest overlap reached "
      << 100.0 * overlap << " % of the diameter, " << 100.0 * overlap / nm.overlap_limit << " % of the limit "
      << 100.0 * nm.overlap_limit << " % at which the run stops (numerics.overlap_limit). Overlaps scale as "
      << "k_n^(-1/2), i.e. with gamma*: ";
    // aim at 0.8 of the threshold: the step that crossed it need not be the impact's deepest
    const double scale = 0.8 * threshold / overlap;
    if (scene_.contact.gamma_star)
      o << "contact.gamma_star = " << *scene_.contact.gamma_star * scale << " (now " << *scene_.contact.gamma_star << ")";
    else
      o << "contact.stiffness = " << scene_.derived.k_n_N_m / scene_.particles.parcel_size / (scale * scale)
        << " N/m (now " << scene_.derived.k_n_N_m / scene_.particles.parcel_size << ")";
    o << " would keep impacts like these below " << 100.0 * threshold
      << " % (with a proportionally shorter DEM step); faster impacts later (clusters) need more";
    series_.add_warning(o.str());
    if (rank_ == 0) std::cerr << o.str() << "\n" << std::flush;
  }

  /// Coupled CFD-DEM: one fluid step, then its DEM sub-steps with the fluid forces held constant
  /// (sim/coupled_step.hpp). The fluid step is a whole number of DEM steps, cut to land on every snapshot
  /// time and the end, so output and restart happen at fluid-step boundaries.
  void time_loop_coupled() {
    begin_loop();
    for (;;) {
      const std::int64_t step = dem_.step_index();
      checkpoint_if_due(step);
      // Ghosts (or a due rebuild) for the current buffers: the series row's contact diagnostics read
      // them. The first sub-step's prepare() then only refreshes them again (same values).
      dem_.prepare();
      coupled_->begin(dem_.particles());
      const bool final_step = step >= end_step_;
      append_series_row(step);
      snapshot_if_due(step, final_step);
      if (final_step) break;
      std::int64_t to_target = end_step_ - step;
      if (dump_every_ > 0) to_target = std::min(to_target, dump_every_ - step % dump_every_);
      or_diagnose([&] {
        const std::int64_t n_sub = coupled_->substeps(step, to_target);
        coupled_->advance(dem_, n_sub, [&] { warn_if_overlap_high(); });
      });
      progress(dem_.step_index(), false);
    }
    progress(end_step_, true);
  }

  void diagnostic_snapshot() {
    // After a failed commit the current buffers hold the failed state; write it as it is.
    const dem::Particles& p = dem_.particles();
    const std::vector<double> diameter(p.n_owned, dem_.settings().diameter_m);
    schema::ParticleFields f;
    f.count = static_cast<std::int64_t>(p.n_owned);
    f.id = p.id.data();
    f.position = p.x.data();
    f.velocity = p.v.data();
    f.angular_velocity = p.rotation ? p.w.data() : nullptr;
    f.diameter = diameter.data();
    const std::int64_t step = dem_.step_index();
    const std::string name = "diagnostic_" + snapshot_name(step).substr(5);
    schema::write_snapshot((dir_ / "snapshots" / name).string(), comm_, scene_, static_cast<double>(step) * dt_, step,
                           f);
    if (rank_ == 0) {
      const fs::path checkpoint = dir_ / "checkpoint.h5";
      std::cerr << "diagnostic snapshot: " << (dir_ / "snapshots" / name).string()
                << (fs::exists(checkpoint) ? "; last good checkpoint kept: " + checkpoint.string()
                                           : std::string("; no checkpoint had been written yet"))
                << "\n";
    }
  }

  /// The series, the timing report (sim/run_report.hpp; max over ranks per phase, for this session and
  /// for the whole run) and the DONE marker, written last. Collective.
  void finish() {
    write_series();
    const std::vector<double> phases = phase_seconds();
    std::vector<double> session(phases.size());
    for (std::size_t k = 0; k < phases.size(); ++k) session[k] = phases[k] - session_start_phases_[k];
    RunReport r;
    r.whole_run_phase_seconds.resize(phases.size());
    r.session_phase_seconds.resize(phases.size());
    MPI_Allreduce(phases.data(), r.whole_run_phase_seconds.data(), static_cast<int>(phases.size()), MPI_DOUBLE, MPI_MAX,
                  comm_);
    MPI_Allreduce(session.data(), r.session_phase_seconds.data(), static_cast<int>(session.size()), MPI_DOUBLE, MPI_MAX,
                  comm_);
    const double wall = elapsed();
    r.wall_s = wall;
    r.session_wall_s = wall_seconds() - wall_start_;
    std::int64_t n_local = static_cast<std::int64_t>(dem_.particles().n_owned), n = 0;
    MPI_Allreduce(&n_local, &n, 1, MPI_INT64_T, MPI_SUM, comm_);
    double bytes = static_cast<double>(dem_.bytes()), total_bytes = 0;
    MPI_Allreduce(&bytes, &total_bytes, 1, MPI_DOUBLE, MPI_SUM, comm_);
    r.peak_bytes = peak_memory_bytes(comm_);
    if (rank_ == 0) {
      r.phase_names = phase_names();
      r.loop_wall_s = wall_seconds() - loop_start_wall_;
      r.end_step = end_step_;
      r.loop_start_step = loop_start_step_;
      r.restarted = restarted_from_ >= 0;
      r.particles = n;
      r.ranks = ranks_;
      r.dem_bytes = total_bytes;
      r.memory_estimate_bytes = memory_estimate_bytes_;
      std::cout << timing_report(r) << std::flush;
    }
    std::ostringstream done;
    done << "completed " << end_step_ << " steps, t = " << static_cast<double>(end_step_) * dt_ << " s, " << n
         << " particles, " << wall << " s wall\n";
    on_rank0(comm_, [&] { write_text_atomically(dir_ / "DONE", done.str()); });
  }

  const Scene& scene_;
  RunSettings settings_;
  MPI_Comm comm_;
  int rank_ = 0, ranks_ = 1;
  fs::path dir_;
  std::unique_ptr<fluid::FluidGrid> grid_;  // the fluid's slabs (the DEM's are its own, balanced)
  dem::DemSystem dem_;
  std::unique_ptr<CoupledStep> coupled_;  // scenes that solve the fluid
  double dt_ = 0;
  std::int64_t end_step_ = 0, dump_every_ = 0, series_every_ = 1;
  schema::Series series_;
  std::vector<checkpoint::Frame> frames_;
  PhaseTimers run_timers_;
  std::size_t t_output_ = 0, t_checkpoint_ = 0, t_diag_ = 0;
  double wall_start_ = wall_seconds(), wall_offset_ = 0, last_checkpoint_wall_ = 0;
  double loop_start_wall_ = 0;
  std::int64_t loop_start_step_ = 0, restarted_from_ = -1;
  std::string placement_method_;
  double placement_gap_ = 0, placement_seconds_ = 0;
  bool overlap_warned_ = false, checkpoint_requested_ = false;
  Progress progress_;
  ProgressPhysics progress_physics_;  // of the latest series row
  std::vector<double> session_start_phases_;  // phase seconds when this session's loop began
  double resident_at_start_ = 0;      // all ranks, after setup (estimate_memory)
  double memory_estimate_bytes_ = 0;  // all ranks: printed in the banner and beside the measured peak, printed in the banner and beside the measured peak
};

}  // namespace

Scene restart_scene(const Scene& scene, const std::string& output_dir, MPI_Comm comm) {
  const fs::path path = fs::path(output_dir) / "checkpoint.h5";
  int rank = 0, exists = 0;
  MPI_Comm_rank(comm, &rank);
  if (rank == 0) exists = fs::exists(path) ? 1 : 0;
  MPI_Bcast(&exists, 1, MPI_INT, 0, comm);
  if (!exists)
    throw InputError(path.string() + ": no checkpoint to restart from (--restart needs a run directory written by " +
                     "an earlier run of this scene)");
  const checkpoint::Header header = checkpoint::read_header(path.string(), comm);
  const std::string& stored = header.scene_toml;
  const std::string& name = header.scene_name;
  const std::vector<std::string> diff = restart_differences(stored, scene.effective_toml);
  if (!diff.empty()) {
    std::string message = scene.source_path + ": the scene differs from the one the run in " + output_dir +
                          " was started with, in " + std::to_string(diff.size()) +
                          " key(s); a restart continues the same simulation, so only run.end_time, "
                          "run.dump_interval, run.series_interval and run.checkpoint_wall_s (or their _tref forms) "
                          "may change (start a new run in another directory for anything else):";
    for (const std::string& d : diff) message += "\n  " + d;
    throw InputError(message);
  }
  Scene out = scene;
  out.name = name;  // restarting from the run's own scene.toml keeps the scene's name
  return out;
}

void run_scene(const Scene& scene, const RunSettings& settings, MPI_Comm comm) {
  // -o naming a file is bad input, refused before anything is written (rank 0's view, shared).
  int rank = 0, not_a_directory = 0;
  MPI_Comm_rank(comm, &rank);
  if (rank == 0) {
    std::error_code ec;
    not_a_directory = fs::exists(settings.output_dir, ec) && !fs::is_directory(settings.output_dir, ec) ? 1 : 0;
  }
  MPI_Bcast(&not_a_directory, 1, MPI_INT, 0, comm);
  if (not_a_directory)
    throw InputError("-o " + settings.output_dir + ": exists and is not a directory; the run directory must be a " +
                     "new or empty directory, or with --restart the directory of an earlier run");
  if (settings.restart) {
    const Scene restarted = restart_scene(scene, settings.output_dir, comm);
    RunDriver driver(restarted, settings, comm);
    driver.run();
    return;
  }
  RunDriver driver(scene, settings, comm);
  driver.run();
}

}  // namespace cgd
