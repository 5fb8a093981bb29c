#include "filter/filter.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <numbers>
#include <optional>
#include <queue>
#include <sstream>

#include "core/cli.hpp"
#include "core/drag.hpp"
#include "core/error.hpp"
#include "core/scene.hpp"
#include "core/timers.hpp"
#include "core/tsc_grid.hpp"
#include "filter/box_filter.hpp"

namespace cgd::filter {

namespace fs = std::filesystem;

namespace {

std::string fmt(double v) {
  std::ostringstream o;
  o.precision(6);
  o << v;
  return o.str();
}

DragLaw micro_law(const RunPlan& run) {
  const std::string& d = run.physics.drag;
  if (const auto law = microscopic_drag_law(d)) return *law;
  throw InputError(run.path + ": the run's drag law is '" + d +
                   "'; the filter normalises by a microscopic law (" + drag_law_names(DragKind::Micro) +
                   "): a resolved run uses one");
}

DragParams drag_params(const schema::RunPhysics& p) { return DragParams{p.fluid_density_kg_m3, p.fluid_viscosity_Pa_s, p.diameter_m}; }

/// splitmix64 (Steele, Lea & Flood 2014): the hash that picks the random per-particle samples.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/// The first difference between two runs that cannot be pooled: their physical system
/// (compare_systems, core/physical_system.hpp: d, densities, viscosity, |g|, u_t, L_char to 1e-6 relative,
/// the law exactly), then the parcel size, the pressure-gradient force, the direction of gravity and the
/// grid spacing (1e-6 relative). {key, value in a, value in b}, or nullopt.
std::optional<std::array<std::string, 3>> pooling_difference(const RunPlan& a, const RunPlan& b) {
  if (const auto d = compare_systems(a.physics.system(), b.physics.system())) return {{d->scene_key, d->first, d->second}};
  const schema::RunPhysics &p = a.physics, &q = b.physics;
  auto same = [](double x, double y) { return std::abs(x - y) <= 1e-6 * std::max(std::abs(x), std::abs(y)); };
  auto triple = [](const std::array<double, 3>& v) { return fmt(v[0]) + "," + fmt(v[1]) + "," + fmt(v[2]); };
  auto same3 = [&](const std::array<double, 3>& x, const std::array<double, 3>& y) {
    return same(x[0], y[0]) && same(x[1], y[1]) && same(x[2], y[2]);
  };
  if (!same(p.parcel_size, q.parcel_size)) return {{"particles.parcel_size", fmt(p.parcel_size), fmt(q.parcel_size)}};
  if (p.pressure_gradient_force != q.pressure_gradient_force)
    return {{"fluid.pressure_gradient_force", p.pressure_gradient_force ? "true" : "false",
             q.pressure_gradient_force ? "true" : "false"}};
  if (!same3(p.gravity_m_s2, q.gravity_m_s2))
    return {{"domain.gravity (m/s^2)", triple(p.gravity_m_s2), triple(q.gravity_m_s2)}};
  if (!same3(a.grid.spacing_m, b.grid.spacing_m))
    return {{"grid spacing (m)", triple(a.grid.spacing_m), triple(b.grid.spacing_m)}};
  return std::nullopt;
}

}  // namespace

std::size_t FilterPlan::snapshot_count() const {
  std::size_t n = 0;
  for (const RunPlan& r : runs) n += r.files.size();
  return n;
}

CoarseGrid coarse_grid_of_scene(const std::string& scene_toml, const std::string& origin, int cells_across) {
  if (cells_across < 1)
    throw InputError("--grids: " + std::to_string(cells_across) + " cells across is not allowed (an integer >= 1)");
  Scene first;
  try {
    first = load_scene_from_string(scene_toml, origin);
  } catch (const std::exception& e) {
    throw InputError("--grids: the scene of " + origin + " cannot be loaded by this build, so the coarse grid a coarse "
                     "run would build is unknown: " + e.what());
  }
  const double d = first.particles.diameter_m;
  const double dx_over_dp = first.domain.size_m[0] / (cells_across * d);
  std::ostringstream set;
  set.precision(17);
  set << "fluid.dx_over_dp=" << dx_over_dp;
  Scene scene;
  try {
    scene = load_scene_from_string(scene_toml, origin, {set.str()});
  } catch (const std::exception& e) {
    throw InputError("--grids: " + std::to_string(cells_across) + " cells across (fluid.dx_over_dp = " + fmt(dx_over_dp) +
                     ") is refused by the scene of " + origin + ": " + e.what());
  }
  if (!scene.fluid) throw InputError("--grids: the scene of " + origin + " has no [fluid] section");
  CoarseGrid c;
  c.cells_across = cells_across;
  c.dx_over_dp = dx_over_dp;
  for (int a = 0; a < 3; ++a) {
    c.grid.cells[a] = scene.fluid->cells[a];
    c.grid.spacing_m[a] = scene.domain.size_m[a] / scene.fluid->cells[a];  // sim/fluid/grid.cpp: h = box / cells
    c.grid.origin_m[a] = 0.0;                                              // the engine's grids start at 0
  }
  c.void_fraction_floor = scene.numerics.void_fraction_floor;
  return c;
}

std::vector<double> coarse_grid_fields(const schema::Snapshot& s, const CoarseGrid& coarse, double particle_volume_m3) {
  const PeriodicGrid& G = coarse.grid;
  // 1. the coarse run's solids fraction: the TSC deposit of the particles' volume, with the floor
  std::vector<double> phi = tsc_deposit_solids_fraction(G, s.position, {particle_volume_m3});
  apply_void_fraction_floor(phi, coarse.void_fraction_floor);
  // 2. the fluid restricted to the coarse cells: exact box averages over each cell of eps, eps u_c, p
  const std::size_t n_fine = s.grid.cell_count();
  std::vector<double> eps_uc(3 * n_fine);
  for (std::size_t c = 0; c < n_fine; ++c)
    for (int d = 0; d < 3; ++d) eps_uc[3 * c + d] = s.void_fraction[c] * s.cell_velocity[3 * c + d];
  const double widest = std::max({G.spacing_m[0], G.spacing_m[1], G.spacing_m[2]});
  const PeriodicBoxFilter fine(s.grid, s.void_fraction, eps_uc, s.pressure, widest);
  const std::size_t n = G.cell_count();
  std::vector<double> p(n), out(7 * n);
  for (int k = 0; k < G.cells[2]; ++k)
    for (int j = 0; j < G.cells[1]; ++j)
      for (int i = 0; i < G.cells[0]; ++i) {
        const std::size_t c = G.index(i, j, k);
        const double centre[3] = {G.origin_m[0] + (i + 0.5) * G.spacing_m[0], G.origin_m[1] + (j + 0.5) * G.spacing_m[1],
                                  G.origin_m[2] + (k + 0.5) * G.spacing_m[2]};
        const FilteredPoint f = fine.at(centre, G.spacing_m);
        out[7 * c] = phi[c];
        for (int d = 0; d < 3; ++d) out[7 * c + 1 + d] = f.velocity[d];  // Favre: box(eps u_c) / box(eps)
        p[c] = f.pressure;
      }
  // 3. the coarse run's cell-centred pressure gradient (central differences, as the coupler)
  const std::vector<double> grad = central_pressure_gradient(G, p);
  for (std::size_t c = 0; c < n; ++c)
    for (int d = 0; d < 3; ++d) out[7 * c + 4 + d] = grad[3 * c + d];
  return out;
}

std::vector<double> coarse_cell_mean_velocity(const schema::Snapshot& s, const CoarseGrid& coarse,
                                              const std::vector<double>& fields) {
  const PeriodicGrid& G = coarse.grid;
  const std::size_t n = G.cell_count();
  std::vector<double> mass(n, 0.0), mv(3 * n, 0.0);
  for (std::int64_t i = 0; i < s.count; ++i) {
    const double* v = &s.velocity[3 * i];
    for_each_tsc_cell(G, &s.position[3 * i], [&](std::size_t c, double w) {
      mass[c] += w;
      for (int d = 0; d < 3; ++d) mv[3 * c + d] += w * v[d];
    });
  }
  std::vector<double> out(3 * n);
  for (std::size_t c = 0; c < n; ++c)
    for (int d = 0; d < 3; ++d) out[3 * c + d] = mass[c] > 0 ? mv[3 * c + d] / mass[c] : fields[7 * c + 1 + d];
  return out;
}

std::vector<double> default_widths_m(const PeriodicGrid& grid, double shortest_edge_m) {
  std::vector<double> w;
  const double h = grid.cell_size_m();
  for (int k = 1; 3.0 * k * h <= shortest_edge_m * (1.0 + 1e-9); ++k) w.push_back(k * h);
  if (w.empty()) w.push_back(h);
  return w;
}

FilterPlan plan_filter(const FilterOptions& o) {
  FilterPlan plan;
  if (o.run_dirs.empty()) throw InputError("cgd-filter: no run directory given (usage: cgd-filter RUN_DIR... -o FILE)");
  if (o.output_path.empty()) throw InputError("cgd-filter: no output file given (-o FILE)");
  if (!(o.bin_width > 0 && o.bin_width <= 0.5))
    throw InputError("--bins: bin width " + fmt(o.bin_width) + " is not allowed (0 < width <= 0.5)");
  if (!(o.bin_max > o.bin_width && o.bin_max <= 1.0))
    throw InputError("--bins: upper end " + fmt(o.bin_max) + " is not allowed (bin width < upper end <= 1)");
  if (o.from_time_s && o.from_tref) throw InputError("--from-time and --from-tref are alternatives: give one");
  if (!(o.slip_bin_width > 0 && o.slip_bin_width <= 10))
    throw InputError("--slip-bins: bin width " + fmt(o.slip_bin_width) + " u_t is not allowed (0 < width <= 10)");
  if (!(o.slip_bin_max > o.slip_bin_width && o.slip_bin_max <= 100 && o.slip_bin_max / o.slip_bin_width <= 1000))
    throw InputError("--slip-bins: upper end " + fmt(o.slip_bin_max) +
                     " u_t is not allowed (bin width < upper end <= 100 u_t, at most 1000 bins)");
  if (o.samples < 0) throw InputError("--samples: " + std::to_string(o.samples) + " is not allowed (>= 0)");
  if (o.bootstrap_replicates < 20)
    throw InputError("--bootstrap: " + std::to_string(o.bootstrap_replicates) +
                     " replicates is not allowed (>= 20; 1000 for a 95 % interval)");
  check_output_file(o.output_path, o.force);

  for (const std::string& dir : o.run_dirs) {
    RunPlan run;
    run.path = dir;
    run.directory = list_run_directory(dir);
    if (run.directory.snapshot_files.empty())
      throw InputError(dir + ": the run has no snapshots (snapshots/snap_<step>.h5); run cgd-generate first");
    if (!run.directory.complete)
      plan.warnings.push_back(dir + ": no DONE marker (the run is in progress or was stopped): filtering its " +
                              std::to_string(run.directory.snapshot_files.size()) + " complete snapshots");
    bool first = true;
    for (const std::string& file : run.directory.snapshot_files) {
      const schema::Snapshot head = schema::read_snapshot(file, schema::SnapshotContent::HeaderOnly);
      if (first) {
        run.physics = head.physics;
        if (!head.has_fluid || !head.physics.has_fluid)
          throw InputError(file + ": the run has no fluid fields (a dry or quiescent-fluid run); the filter needs a "
                                  "coupled CFD-DEM run (fluid.coupling = \"two-way\" or \"one-way\")");
        run.grid = head.grid;
        first = false;
      }
      double from = 0;
      if (o.from_time_s) from = *o.from_time_s;
      if (o.from_tref) from = *o.from_tref * run.physics.t_ref_s;
      if (head.time_s < from * (1.0 - 1e-12)) continue;
      run.files.push_back(file);
      run.times_s.push_back(head.time_s);
      run.steps.push_back(head.step);
    }
    if (run.files.empty())
      throw InputError(dir + ": no snapshot at or after the --from time (" +
                       (o.from_tref ? fmt(*o.from_tref) + " t_ref" : fmt(*o.from_time_s) + " s") +
                       "); the run's snapshots end at step " + std::to_string(run.directory.steps.back()));
    micro_law(run);  // refuses filtered laws
    if (!plan.runs.empty())
      if (const auto d = pooling_difference(plan.runs.front(), run))
        throw InputError("runs of different physics cannot be pooled: " + (*d)[0] + " is " + (*d)[1] + " in " +
                         plan.runs.front().path + " but " + (*d)[2] + " in " + dir +
                         " (pooled runs share particles, fluid, drag law and grid spacing; <phi_p> and the box may differ)");
    plan.runs.push_back(std::move(run));
  }

  const RunPlan& r0 = plan.runs.front();
  double shortest = 1e300;
  for (const RunPlan& r : plan.runs)
    for (int a = 0; a < 3; ++a) shortest = std::min(shortest, r.grid.edge_m(a));
  const double d = r0.physics.diameter_m;
  const double h_max = std::max({r0.grid.spacing_m[0], r0.grid.spacing_m[1], r0.grid.spacing_m[2]});
  if (o.widths_over_dp.empty()) {
    plan.widths_m = default_widths_m(r0.grid, shortest);
  } else {
    for (double w : o.widths_over_dp) {
      double wm = w * d;
      // widths typed with 3 digits (3.33 for a cell of 3.333 d_p) mean the limit: within 0.5 %, clamp
      if (wm < h_max && wm >= h_max * (1.0 - 5e-3)) wm = h_max;
      if (wm > shortest && wm <= shortest * (1.0 + 5e-3)) wm = shortest;
      if (!(wm >= h_max * (1.0 - 1e-9)) || !(wm <= shortest * (1.0 + 1e-9)))
        throw InputError("--widths: " + fmt(w) + " d_p is not allowed: a filter width lies between one cell (" +
                         fmt(h_max / d) + " d_p) and the shortest box edge (" + fmt(shortest / d) + " d_p)");
      plan.widths_m.push_back(wm);
    }
    std::sort(plan.widths_m.begin(), plan.widths_m.end());
    plan.widths_m.erase(std::unique(plan.widths_m.begin(), plan.widths_m.end()), plan.widths_m.end());
  }
  // coarse grids: each run's own (a coarse run of that run's box), all runs the same cell
  {
    std::vector<int> grids = o.grids_cells_across;
    std::sort(grids.begin(), grids.end(), std::greater<int>());  // ascending cell size
    grids.erase(std::unique(grids.begin(), grids.end()), grids.end());
    plan.grids = grids;
    for (RunPlan& r : plan.runs)
      for (int n : grids) {
        CoarseGrid c = coarse_grid_of_scene(r.physics.scene_toml, r.path, n);
        for (int a = 0; a < 3; ++a)
          if (c.grid.spacing_m[a] < r.grid.spacing_m[a] * (1.0 - 1e-9))
            throw InputError("--grids: " + std::to_string(n) + " cells across gives " + std::to_string(c.grid.cells[a]) +
                             " cells of " + fmt(c.grid.spacing_m[a] / d) + " d_p along " + "xyz"[a] + " for " + r.path +
                             ", finer than the run's own " + fmt(r.grid.spacing_m[a] / d) +
                             " d_p: a coarse grid has at most the resolved grid's " + std::to_string(r.grid.cells[0]) +
                             " cells across");
        if (&r != &plan.runs.front()) {
          const CoarseGrid& f0 = plan.runs.front().coarse[r.coarse.size()];
          for (int a = 0; a < 3; ++a)
            if (std::abs(c.grid.spacing_m[a] - f0.grid.spacing_m[a]) > 1e-9 * f0.grid.spacing_m[a])
              throw InputError("--grids: " + std::to_string(n) + " cells across gives cells of " +
                               fmt(f0.grid.spacing_m[a] / d) + " d_p along " + "xyz"[a] + " in " +
                               plan.runs.front().path + " but " + fmt(c.grid.spacing_m[a] / d) + " d_p in " + r.path +
                               " (pooled runs need boxes that give the same coarse cell)");
        }
        r.coarse.push_back(c);
      }
  }
  plan.whole_box_width_m = std::cbrt(r0.physics.box_size_m[0] * r0.physics.box_size_m[1] * r0.physics.box_size_m[2]);
  const int n_bins = static_cast<int>(std::llround(o.bin_max / o.bin_width));
  for (int b = 0; b <= n_bins; ++b) plan.bin_edges.push_back(b * o.bin_width);
  if (!plan.grids.empty()) {  // the drift table's slip bins, in u_t
    const int n_slip = static_cast<int>(std::llround(o.slip_bin_max / o.slip_bin_width));
    for (int m = 0; m <= n_slip; ++m) plan.slip_edges.push_back(m * o.slip_bin_width);
    if (!(r0.physics.u_t_m_s > 0))
      throw InputError(r0.path + ": the run has no terminal velocity u_t > 0 (a fluid and gravity): the drift sums "
                       "of --grids bin the cell slip in u_t");
  }
  return plan;
}

SnapshotResult filter_snapshot(const schema::Snapshot& s, const FilterPlan& plan, const FilterOptions& o,
                               std::int64_t snapshot_row, std::size_t run_index) {
  const RunPlan& run = plan.runs[run_index];
  if (s.drag_coefficient.empty() || !s.has_fluid)
    throw InputError(s.path + ": the snapshot lacks the coupling fields (/particles/drag_coefficient, /fluid); "
                              "the filter needs a coupled run's snapshot");
  if (!plan.grids.empty() && s.cell_velocity.size() != 3 * s.grid.cell_count())
    throw InputError(s.path + ": the snapshot lacks /fluid/velocity (the cell-centred u the coarse-grid operator restricts)");
  const double t0 = wall_seconds();
  const std::size_t n_widths = plan.columns();  // widths, whole box, grids
  const std::size_t whole_col = plan.whole_box_column();
  const std::size_t n_bins = plan.bin_edges.size() - 1;
  const double bin_width = plan.bin_edges[1] - plan.bin_edges[0];
  SnapshotResult out;
  out.sums.assign(n_widths * n_bins, BinSums{});
  out.out_of_range.assign(n_widths, 0);
  out.samples.assign(n_widths, {});
  out.particles = s.count;
  const std::size_t n_slip = plan.slip_bins();
  out.drift.assign(plan.grids.size() * n_bins * n_slip, DriftSums{});
  out.drift_out_of_range.assign(plan.grids.size(), 0);
  const double slip_bin_width = n_slip > 0 ? plan.slip_edges[1] - plan.slip_edges[0] : 1.0;
  const double inv_u_t = 1.0 / run.physics.u_t_m_s;
  const PeriodicBoxFilter box(s.grid, s.void_fraction, s.eps_velocity, s.pressure,
                              plan.widths_m.empty() ? s.grid.cell_size_m() : plan.widths_m.back());
  // the coarse grids' fields (phi, u, grad p per coarse cell), interpolated to the particles below
  std::vector<std::vector<double>> coarse(plan.grids.size());
  const double particle_volume = std::numbers::pi / 6.0 * std::pow(run.physics.diameter_m * run.physics.parcel_size, 3);
  for (std::size_t g = 0; g < plan.grids.size(); ++g) coarse[g] = coarse_grid_fields(s, run.coarse[g], particle_volume);
  // the grids' cell-mean particle velocities (the drift sums)
  std::vector<std::vector<double>> vbar(plan.grids.size());
  for (std::size_t g = 0; g < plan.grids.size(); ++g) vbar[g] = coarse_cell_mean_velocity(s, run.coarse[g], coarse[g]);
  const FilteredPoint whole = box.domain_average();
  const bool pressure_terms = run.physics.pressure_gradient_force;
  // max-heaps of the smallest keys per width: the random subsample
  auto by_key = [](const Sample& a, const Sample& b) { return a.key < b.key; };
  std::vector<std::priority_queue<Sample, std::vector<Sample>, decltype(by_key)>> heaps(n_widths, decltype(heaps)::value_type(by_key));

  // particles in cell order, so that neighbours in the loop read neighbouring table points (the order
  // is a function of the snapshot alone: results do not depend on how snapshots go to ranks)
  std::vector<std::pair<std::size_t, std::int64_t>> order(static_cast<std::size_t>(s.count));
  for (std::int64_t i = 0; i < s.count; ++i) {
    int c[3];
    for (int a = 0; a < 3; ++a)
      c[a] = std::min(s.grid.cells[a] - 1, static_cast<int>(s.grid.wrapped_cell_coordinate(s.position[3 * i + a], a)));
    order[static_cast<std::size_t>(i)] = {s.grid.index(c[0], c[1], c[2]), i};
  }
  std::sort(order.begin(), order.end());

  visit_drag_law(micro_law(run), drag_params(run.physics), [&](const auto& law) {
    for (const auto& [cell, i] : order) {
      const double* x = &s.position[3 * i];
      const double* v = &s.velocity[3 * i];
      const double* u = &s.fluid_velocity[3 * i];
      const double resolved = s.drag_coefficient[i] * (u[1] - v[1]) - (pressure_terms ? s.pressure_gradient[3 * i + 1] : 0.0);
      for (std::size_t w = 0; w < n_widths; ++w) {
        FilteredPoint f;
        if (w < whole_col) {
          f = box.at(x, plan.widths_m[w]);
        } else if (w == whole_col) {
          f = whole;
        } else {  // a coarse grid: TSC interpolation of its cell fields, as Coupler::compute_drag
          const std::size_t g = w - whole_col - 1;
          const std::array<double, 7> c = tsc_interpolate<7>(run.coarse[g].grid, coarse[g].data(), x);
          f.void_fraction = 1.0 - c[0];
          for (int d = 0; d < 3; ++d) f.velocity[d] = c[1 + d], f.grad_p[d] = c[4 + d];
        }
        const double phi = 1.0 - f.void_fraction;
        const double slip[3] = {f.velocity[0] - v[0], f.velocity[1] - v[1], f.velocity[2] - v[2]};
        const double speed = std::sqrt(slip[0] * slip[0] + slip[1] * slip[1] + slip[2] * slip[2]);
        const double numerator = resolved + (pressure_terms ? f.grad_p[1] : 0.0);
        const double beta_micro = law.beta_p(std::clamp(phi, 0.0, 0.99), speed);
        const double b_real = std::floor(phi / bin_width);
        if (!(b_real >= 0 && b_real < static_cast<double>(n_bins))) {
          ++out.out_of_range[w];
        } else {
          BinSums& bs = out.sums[w * n_bins + static_cast<std::size_t>(b_real)];
          bs.count += 1;
          bs.numerator += numerator;
          bs.micro += beta_micro * slip[1];
          bs.slip += slip[1];
          bs.phi += phi;
          if (w > whole_col && n_slip > 0) {  // a grid: the drift sums, binned in phi~ and the cell slip
            const std::size_t g = w - whole_col - 1;
            const std::array<double, 3> vb = tsc_interpolate<3>(run.coarse[g].grid, vbar[g].data(), x);
            const double cell[3] = {f.velocity[0] - vb[0], f.velocity[1] - vb[1], f.velocity[2] - vb[2]};
            const double cell_speed = std::sqrt(cell[0] * cell[0] + cell[1] * cell[1] + cell[2] * cell[2]);
            const double shat = cell_speed * inv_u_t;
            const double m_real = std::floor(shat / slip_bin_width);
            if (!(m_real >= 0 && m_real < static_cast<double>(n_slip))) {
              ++out.drift_out_of_range[g];
            } else {
              DriftSums& ds = out.drift[(g * n_bins + static_cast<std::size_t>(b_real)) * n_slip +
                                        static_cast<std::size_t>(m_real)];
              ds.count += 1;
              ds.numerator += beta_micro * slip[1] - numerator;
              ds.denominator += beta_micro * cell[1];
              ds.magnitude += beta_micro * cell_speed;
              ds.phi += phi;
              ds.slip += shat;
            }
          }
        }
        if (o.samples > 0) {
          Sample smp;
          smp.key = mix(o.seed ^ mix(run_index * 0x100000001b3ull ^ mix(static_cast<std::uint64_t>(s.step) ^
                                                                        mix(static_cast<std::uint64_t>(s.id[i]) * 131 + w))));
          auto& heap = heaps[w];
          if (static_cast<std::int64_t>(heap.size()) < o.samples || smp.key < heap.top().key) {
            smp.snapshot = snapshot_row;
            smp.id = s.id[i];
            smp.phi = phi;
            smp.numerator = numerator;
            smp.beta_micro = beta_micro;
            for (int d = 0; d < 3; ++d) {
              smp.slip[d] = slip[d];
              smp.grad_p_filtered[d] = f.grad_p[d];
            }
            heap.push(smp);
            if (static_cast<std::int64_t>(heap.size()) > o.samples) heap.pop();
          }
        }
      }
    }
  });
  for (std::size_t w = 0; w < n_widths; ++w)
    while (!heaps[w].empty()) {
      out.samples[w].push_back(heaps[w].top());
      heaps[w].pop();
    }
  out.seconds = wall_seconds() - t0;
  return out;
}

}  // namespace cgd::filter
