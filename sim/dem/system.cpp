#include "sim/dem/system.hpp"

#include <cmath>
#include <cstring>
#include <sstream>
#include <type_traits>

#include "core/error.hpp"

namespace cgd::dem {

DemSystem::DemSystem(const DemSettings& settings, MPI_Comm comm)
    : s_(settings),
      slabs_(settings.slab_lower_bounds.empty() ? SlabDecomposition(comm, settings.box_m)
                                                : SlabDecomposition(comm, settings.box_m, settings.slab_lower_bounds)),
      ghosts_(slabs_) {
  p_.rotation = s_.contacts && s_.friction;
  p_.external = s_.per_particle_drive;
  const double radius = 0.5 * s_.diameter_m;
  kc_.dt = s_.dt_s;
  kc_.radius = radius;
  kc_.inv_mass = 1.0 / s_.mass_kg;
  kc_.inv_inertia = 1.0 / (0.4 * s_.mass_kg * radius * radius);  // solid sphere: I = 2/5 m r^2
  s_.contact.dt = s_.dt_s;
  // free flight: with a per-particle drive, or the uniform one whose drag keeps lambda dt <= 1/2 (the scene
  // refuses more; the speed bound of select_free_flight needs 1 - lambda dt >= 0)
  free_flight_ = s_.per_particle_drive || s_.drive.drag_rate * s_.dt_s <= 0.5;
  t_neigh_ = timers_.add("neighbor");
  t_comm_ = timers_.add("comm");
  t_force_ = timers_.add("force+integrate");
  skin_m_ = skin_min_m_ = skin_max_m_ = s_.skin_m;
  if (s_.skin_target_steps > 0) {
    skin_min_m_ = s_.skin_min_m;
    skin_max_m_ = std::max(s_.skin_min_m, s_.skin_max_m);
    skin_m_ = std::clamp(s_.skin_m, skin_min_m_, skin_max_m_);
  }
  // an anchor is a float: its rounding (at most 2^-24 of the largest coordinate, in [0, L) after the wrap)
  // comes off every reach, four times over
  anchor_margin_m_ = std::ldexp(std::max({s_.box_m[0], s_.box_m[1], s_.box_m[2]}), -22);
  {
    // the thinnest first slab of all ranks (given bounds may be uneven): every rank decides alike (no rank left waiting)
    double slab = slabs_.y_hi() - slabs_.y_lo();
    MPI_Allreduce(MPI_IN_PLACE, &slab, 1, MPI_DOUBLE, MPI_MIN, slabs_.comm());
    thinnest_slab_m_ = slab;
  }
  if (s_.contacts) {
    const double slab = thinnest_slab_m_;
    // an adaptive skin never outgrows the thinnest slab (ghosts come from the neighbouring rank only)
    if (s_.skin_target_steps > 0 && slab - s_.diameter_m >= skin_min_m_) {
      skin_max_m_ = std::min(skin_max_m_, slab - s_.diameter_m);
      skin_m_ = std::min(skin_m_, skin_max_m_);
    }
    if (slab < cutoff())
      throw InputError("too many MPI ranks (" + std::to_string(slabs_.size()) + ") for the box: each y-slab (the thinnest " +
                       std::to_string(slab) + " m) must be at least one contact cutoff (" +
                       std::to_string(cutoff()) + " m) high; use at most " +
                       std::to_string(static_cast<int>(s_.box_m[1] / cutoff())) + " ranks");
  }
  // balanced slabs: thick enough for every list the skins allow, mid-interval restarts included (d + 2 skin), or
  // equal when the box is too low for that (the skin is then clamped to the thinnest slab above, as for equal slabs)
  min_slab_m_ = std::min(s_.diameter_m + 2.0 * skin_max_m_, s_.box_m[1] / slabs_.size());
}

void DemSystem::set_slab_bounds(const std::vector<double>& lower_bounds) {
  slabs_.set_lower_bounds(lower_bounds);
  thinnest_slab_m_ = slabs_.thinnest();
  if (s_.contacts && thinnest_slab_m_ < cutoff())
    throw InputError("slab bounds: the thinnest slab (" + std::to_string(thinnest_slab_m_) +
                     " m) is thinner than the contact cutoff (" + std::to_string(cutoff()) + " m)");
}

void DemSystem::balance_slabs() {
  const int size = slabs_.size();
  if (size == 1) return;
  const double L = s_.box_m[1];
  // each particle weighs 1 + 4 (m - 1), m the owned particles in its cell of a coarse grid of cells about the
  // cutoff wide: its expected list entries (a sphere of the cutoff holds about 4 such cells), from the positions
  // alone (integers: the sums are exact)
  // (at most kBalanceCells cells: a larger box gets coarser cells, its weights a rougher estimate)
  const double volume = s_.box_m[0] * s_.box_m[1] * s_.box_m[2];
  const double cell = std::max(s_.diameter_m + skin_max_m_, std::cbrt(volume / kBalanceCells));
  int nc[3];
  for (int a = 0; a < 3; ++a) nc[a] = std::max(1, static_cast<int>(s_.box_m[a] / cell));
  auto cell_of = [&](std::size_t i) {
    std::size_t c = 0;
    for (int a = 2; a >= 0; --a) {
      const int k = std::clamp(static_cast<int>(p_.x[3 * i + a] / s_.box_m[a] * nc[a]), 0, nc[a] - 1);
      c = c * static_cast<std::size_t>(nc[a]) + static_cast<std::size_t>(k);
    }
    return c;
  };
  std::vector<std::int32_t> occupancy(static_cast<std::size_t>(nc[0]) * nc[1] * nc[2], 0);
  for (std::size_t i = 0; i < p_.n_owned; ++i) ++occupancy[cell_of(i)];
  std::vector<std::int64_t> hist(kBalanceBins, 0);
  for (std::size_t i = 0; i < p_.n_owned; ++i) {
    const int b = static_cast<int>(p_.x[3 * i + 1] / L * kBalanceBins);  // wrapped: y in [0, L)
    hist[static_cast<std::size_t>(std::clamp(b, 0, kBalanceBins - 1))] += 1 + 4 * (occupancy[cell_of(i)] - 1);
  }
  MPI_Allreduce(MPI_IN_PLACE, hist.data(), kBalanceBins, MPI_INT64_T, MPI_SUM, slabs_.comm());
  std::int64_t total = 0;
  for (std::int64_t c : hist) total += c;
  // rank r's lower bound at the r/size quantile, interpolated within its bin
  std::vector<double> lower(static_cast<std::size_t>(size), 0.0);
  std::int64_t below = 0;  // particles in the bins before b
  int b = 0;
  for (int r = 1; r < size; ++r) {
    const double target = static_cast<double>(total) * r / size;
    while (b < kBalanceBins && static_cast<double>(below + hist[b]) < target) below += hist[b++];
    const double within = b < kBalanceBins && hist[b] > 0 ? (target - static_cast<double>(below)) / static_cast<double>(hist[b]) : 0.0;
    lower[r] = (static_cast<double>(b) + within) * L / kBalanceBins;
  }
  // no slab thinner than min_slab_m_ (the box holds size of them): up from the bottom, then down from the top
  for (int r = 1; r < size; ++r) lower[r] = std::max(lower[r], lower[r - 1] + min_slab_m_);
  for (int r = size - 1; r >= 1; --r) lower[r] = std::min(lower[r], (r == size - 1 ? L : lower[r + 1]) - min_slab_m_);
  slabs_.set_lower_bounds(lower);
  thinnest_slab_m_ = slabs_.thinnest();
}

void DemSystem::set_particles(std::vector<std::int64_t> ids, std::vector<double> x, std::vector<double> v,
                              std::vector<double> w) {
  const std::size_t n = ids.size();
  p_.resize(n, n);
  std::copy(ids.begin(), ids.end(), p_.id.begin());
  std::copy(x.begin(), x.end(), p_.x.begin());
  std::copy(v.begin(), v.end(), p_.v.begin());
  if (p_.rotation) {
    if (w.empty()) std::fill(p_.w.begin(), p_.w.end(), 0.0);
    else std::copy(w.begin(), w.end(), p_.w.begin());
  }
  store_.clear();
  store_.offset.assign(n + 1, 0);
  anchor_.assign(4 * n, 0.0f);  // no reach until the first build (which is due): a checkpoint now says so
  list_valid_ = false;
  rebuild_due_ = true;
  dormant_.clear();
  integrate_.clear();
  selection_due_ = true;
}

void DemSystem::restore(ContactStore store, std::vector<float> anchors, bool rebuild_due, std::int64_t step,
                        std::int64_t last_sort_step) {
  store_ = std::move(store);
  if (store_.offset.size() != p_.n_owned + 1) store_.offset.assign(p_.n_owned + 1, 0);
  anchor_ = std::move(anchors);
  // without the anchors of every particle (an older checkpoint) nothing bounds the moves since the last
  // build: rebuild at once (the trajectory then differs from the uninterrupted run's at round-off)
  rebuild_due_ = rebuild_due || anchor_.size() != 4 * p_.n_owned;
  step_ = step;
  last_sort_step_ = last_sort_step;
  list_valid_ = false;
  dormant_.clear();
  integrate_.clear();
  selection_due_ = true;
}

void DemSystem::prepare() {
  if (rebuild_due_) {  // without contacts: only wrap and migrate (no ghosts, no neighbour search)
    ScopedPhase t(timers_, t_neigh_);
    catch_up();
    full_rebuild();
  } else if (!s_.contacts) {
    return;
  } else if (!list_valid_) {  // a restart between rebuilds
    ScopedPhase t(timers_, t_neigh_);
    catch_up();
    // its list reaches d + 2 skin: beyond the thinnest slab the ghosts would miss pairs, so rebuild instead
    if (s_.diameter_m + 2.0 * skin_m_ > thinnest_slab_m_) full_rebuild();
    else build_ghosts_and_list(true);
  } else {
    ScopedPhase t(timers_, t_comm_);
    ghosts_.forward(p_);
  }
}

void DemSystem::full_rebuild() {
  if (list_valid_ && p_.rotation) list_.save_history(p_, store_);
  for (std::size_t i = 0; i < p_.n_owned; ++i) slabs_.wrap(&p_.x[3 * i]);
  if (s_.balance_slabs) balance_slabs();
  ghosts_.migrate(p_, store_);
  if (last_sort_step_ < 0 || step_ - last_sort_step_ >= s_.sort_interval_steps) {
    // Reorder owned particles by cell for memory locality. Results do not depend on the order.
    const std::vector<std::int32_t> order = spatial_order(p_, cutoff());
    Particles sorted;
    sorted.rotation = p_.rotation;
    sorted.external = p_.external;
    sorted.resize(p_.n_owned, p_.n_owned);
    ContactStore sorted_store;
    const bool has_store = store_.offset.size() == p_.n_owned + 1;
    for (std::size_t k = 0; k < order.size(); ++k) {
      const std::size_t i = static_cast<std::size_t>(order[k]);
      sorted.id[k] = p_.id[i];
      std::memcpy(&sorted.x[3 * k], &p_.x[3 * i], 3 * sizeof(double));
      std::memcpy(&sorted.v[3 * k], &p_.v[3 * i], 3 * sizeof(double));
      if (p_.rotation) std::memcpy(&sorted.w[3 * k], &p_.w[3 * i], 3 * sizeof(double));
      if (p_.external) std::memcpy(&sorted.a_ext[3 * k], &p_.a_ext[3 * i], 3 * sizeof(double));
      if (has_store) {
        for (std::int64_t e = store_.offset[i]; e < store_.offset[i + 1]; ++e) {
          sorted_store.partner.push_back(store_.partner[e]);
          sorted_store.xi.insert(sorted_store.xi.end(), &store_.xi[3 * e], &store_.xi[3 * e + 3]);
        }
        sorted_store.offset.push_back(static_cast<std::int64_t>(sorted_store.partner.size()));
      }
    }
    p_ = std::move(sorted);
    if (has_store) store_ = std::move(sorted_store);
    last_sort_step_ = step_;
  }
  {
    // the largest half-skin (of the fastest particle on any rank: a maximum, the same on every rank count)
    // sets the binning and the ghost shell (the reordering above binned by the last build's)
    double largest = set_anchors();
    MPI_Allreduce(MPI_IN_PLACE, &largest, 1, MPI_DOUBLE, MPI_MAX, slabs_.comm());
    skin_m_ = 2.0 * largest;
  }
  if (s_.contacts) build_ghosts_and_list(false);
  else classify(nullptr);
  rebuild_due_ = false;
  ++rebuilds_;
}

namespace {

/// The float nearest `a` toward zero / toward +infinity (a >= 0): a bound rounded the safe way.
float float_down(double a) {
  float f = static_cast<float>(a);
  if (static_cast<double>(f) > a) f = std::nextafter(f, 0.0f);
  return std::max(f, 0.0f);
}
float float_up(double a) {
  float f = static_cast<float>(a);
  if (static_cast<double>(f) < a) f = std::nextafter(f, HUGE_VALF);
  return f;
}

}  // namespace

double DemSystem::half_skin(double speed) const {
  if (s_.skin_target_steps <= 0) return 0.5 * s_.skin_m;
  return std::clamp(static_cast<double>(s_.skin_target_steps) * s_.dt_s * speed, 0.5 * skin_min_m_, 0.5 * skin_max_m_);
}

double DemSystem::set_anchors() {
  anchor_.resize(4 * p_.n_owned);
  if (s_.contacts) half_skin_.resize(p_.n_owned);  // the ghosts' follow in build_ghosts_and_list
  double largest = 0;
  for (std::size_t i = 0; i < p_.n_owned; ++i) {
    const V3 v = load3(&p_.v[3 * i]);
    const double h = half_skin(std::sqrt(dot(v, v)));
    largest = std::max(largest, h);
    for (int c = 0; c < 3; ++c) anchor_[4 * i + c] = static_cast<float>(p_.x[3 * i + c]);
    anchor_[4 * i + 3] = float_down(h - anchor_margin_m_);
    if (s_.contacts) half_skin_[i] = float_up(h);
  }
  return largest;
}

void DemSystem::build_ghosts_and_list(bool mid_interval) {
  // mid interval: each side of a pair may have moved up to skin/2 and may move up to skin/2 more (its reach
  // twice), so every particle is given the half-skin `skin`; otherwise its own: the owned particles' from
  // set_anchors, a ghost's from the speed it has now, the same bits its owner's came from (the ghost was
  // copied at this build)
  const double shell = s_.diameter_m + (mid_interval ? 2.0 : 1.0) * skin_m_;
  ghosts_.build(p_, shell);
  half_skin_.resize(p_.n_total);
  if (mid_interval) {
    std::fill(half_skin_.begin(), half_skin_.end(), float_up(skin_m_));
  } else {
    for (std::size_t i = p_.n_owned; i < p_.n_total; ++i) {
      const V3 v = load3(&p_.v[3 * i]);
      half_skin_[i] = float_up(half_skin(std::sqrt(dot(v, v))));
    }
  }
  list_.build(p_, shell, s_.diameter_m, half_skin_.data(), p_.rotation);
  if (p_.rotation) list_.load_history(p_, store_);
  list_valid_ = true;
  classify(&list_);
}

void DemSystem::classify(const NeighborList* list) {
  const std::size_t n = p_.n_owned;
  force_rows_.clear();
  referenced_.assign(p_.n_total, 0);
  if (list) {
    for (std::int32_t j : list->index) referenced_[static_cast<std::size_t>(j & NeighborList::kPartnerMask)] = 1;
    for (std::size_t i = 0; i < n; ++i)
      if (list->offset[i + 1] > list->offset[i]) {
        referenced_[i] = 1;
        force_rows_.push_back(static_cast<std::int32_t>(i));
      }
    ghosts_.restrict_forward(referenced_);  // flags the owned sources of referenced ghosts (any rank)
  }
  referenced_.resize(n);
  force_.assign(3 * force_rows_.size(), 0.0);  // per row (integrator.hpp)
  if (p_.rotation) torque_.assign(3 * force_rows_.size(), 0.0);
  dormant_.clear();
  integrate_.clear();
  selection_due_ = true;
}

template <class F>
void DemSystem::with_drive(F&& f) const {
  if (s_.per_particle_drive) f(PerParticleDrive{p_.a_ext.data()});
  else f(s_.drive);
}

void DemSystem::catch_up() const {
  if (dormant_step_ >= step_ || dormant_.empty()) {
    dormant_step_ = step_;
    return;
  }
  const std::int64_t steps = step_ - dormant_step_;
  double* x = p_.x.data();
  double* v = p_.v.data();
  const V3 zero{0, 0, 0};
  // Blocks of kBlock particles side by side (structure of arrays), so that the steps' dependent
  // kick -> drift chains of different particles run in parallel (SIMD lanes) instead of one particle's
  // chain after another: the same operations on the same values as kick_drift, step by step.
  constexpr std::size_t kBlock = 8;
  const std::size_t nd = dormant_.size();
  const double dt = kc_.dt;
  with_drive([&](const auto& drive) {
    using Drive = std::decay_t<decltype(drive)>;
    for (std::size_t b0 = 0; b0 < nd; b0 += kBlock) {
      const std::size_t nb = std::min(kBlock, nd - b0);
      std::size_t idx[kBlock];
      alignas(64) double X[3][kBlock], V[3][kBlock], DA[3][kBlock];
      for (std::size_t m = 0; m < kBlock; ++m) {
        idx[m] = static_cast<std::size_t>(dormant_[b0 + std::min(m, nb - 1)]);  // short block: repeat the last
        for (int c = 0; c < 3; ++c) {
          X[c][m] = x[3 * idx[m] + c];
          V[c][m] = v[3 * idx[m] + c];
        }
      }
      if constexpr (std::is_same_v<Drive, PerParticleDrive>) {
        // a = F/m + a_ext with F = 0 does not depend on v: dt a once (kicked_velocity's own expressions)
        for (std::size_t m = 0; m < kBlock; ++m) {
          const V3 a = kc_.inv_mass * zero + drive(idx[m], zero);
          DA[0][m] = dt * a.x;
          DA[1][m] = dt * a.y;
          DA[2][m] = dt * a.z;
        }
        for (std::int64_t k = 0; k < steps; ++k)
          for (int c = 0; c < 3; ++c)
            for (std::size_t m = 0; m < kBlock; ++m) {
              V[c][m] = V[c][m] + DA[c][m];
              X[c][m] = X[c][m] + dt * V[c][m];
            }
      } else {
        for (std::int64_t k = 0; k < steps; ++k)
          for (std::size_t m = 0; m < kBlock; ++m) {
            const V3 vn = kicked_velocity(idx[m], V3{V[0][m], V[1][m], V[2][m]}, zero, drive, kc_);
            V[0][m] = vn.x;
            V[1][m] = vn.y;
            V[2][m] = vn.z;
            X[0][m] = X[0][m] + dt * vn.x;
            X[1][m] = X[1][m] + dt * vn.y;
            X[2][m] = X[2][m] + dt * vn.z;
          }
      }
      for (std::size_t m = 0; m < nb; ++m) {
        const std::size_t i = idx[m];
        for (int c = 0; c < 3; ++c) {
          x[3 * i + c] = X[c][m];
          v[3 * i + c] = V[c][m];
        }
        // the spin's kick by a zero torque (once is every time: w + 0 does not change after the first)
        if (p_.rotation) store3(&p_.w[3 * i], kicked_spin(load3(&p_.w[3 * i]), zero, kc_));
      }
    }
  });
  dormant_step_ = step_;
}

void DemSystem::select_free_flight() {
  const std::size_t n = p_.n_owned;
  integrate_.clear();
  dormant_.clear();
  selection_step_ = step_;
  dormant_step_ = step_;
  selection_due_ = false;
  if (!free_flight_) {
    integrate_.resize(n);
    for (std::size_t i = 0; i < n; ++i) integrate_[i] = static_cast<std::int32_t>(i);
    return;
  }
  // |v_k| <= |v_0| + k dt A for k <= kHorizon steps, A a bound on |a| over them, widened by 1e-9 (the
  // rounding of 100 steps is ~1e-14 of it). A per-particle drive is constant: A = |a|. The uniform drive
  // a = g - lambda v: with 0 <= lambda dt <= 1/2, |v_{k+1}| <= (1 - lambda dt)|v_k| + dt |g|, so |v_k| <=
  // max(|v_0|, |g|/lambda) and A = |g| + lambda max(|v_0|, |g|/lambda). After m steps the particle is then
  // at most m dt upper from where it is now: it may wait k = (reach - |x - anchor|) / (dt upper) steps before
  // it could leave its anchor's reach (which would call for a rebuild), and the selection is renewed after
  // the fewest steps any waiting particle may wait. A particle that may wait fewer than kMinWait steps is
  // integrated every step (checked exactly there) rather than renewing the selection that often.
  const double h = static_cast<double>(kHorizon) * s_.dt_s;
  constexpr double kSlack = 1e-9;
  const auto accel_bound = [&](const auto& drive, std::size_t i, V3 v, double s) {
    if constexpr (std::is_same_v<std::decay_t<decltype(drive)>, PerParticleDrive>) {
      const V3 a = drive(i, v);
      return std::sqrt(dot(a, a));
    } else {
      const double g = std::sqrt(dot(drive.accel, drive.accel)), lambda = drive.drag_rate;
      return lambda > 0 ? g + lambda * std::max(s, g / lambda) : g;
    }
  };
  std::int64_t horizon = kHorizon;
  with_drive([&](const auto& drive) {
    for (std::size_t i = 0; i < n; ++i) {
      bool every_step = referenced_[i] != 0;
      if (!every_step) {
        const V3 v = load3(&p_.v[3 * i]);
        const double s = std::sqrt(dot(v, v)), A = accel_bound(drive, i, v, s);
        const double upper = (s + h * A) * (1.0 + kSlack);
        const V3 dx = load3(&p_.x[3 * i]) - V3{anchor_[4 * i], anchor_[4 * i + 1], anchor_[4 * i + 2]};
        const double room = static_cast<double>(anchor_[4 * i + 3]) - std::sqrt(dot(dx, dx)) * (1.0 + kSlack);
        // steps it may wait (kHorizon when nothing moves it); NaN and infinities fail the comparison
        const double steps = upper > 0.0 ? room / (s_.dt_s * upper) : (room >= 0.0 ? HUGE_VAL : -1.0);
        every_step = !(steps >= static_cast<double>(kMinWait));
        if (!every_step) horizon = std::min(horizon, static_cast<std::int64_t>(std::min(steps, static_cast<double>(kHorizon))));
      }
      (every_step ? integrate_ : dormant_).push_back(static_cast<std::int32_t>(i));
    }
  });
  selection_horizon_ = horizon;
}

void DemSystem::advance() {
  ScopedPhase t(timers_, t_force_);
  if (selection_due_ || step_ - selection_step_ >= selection_horizon_) {
    catch_up();
    select_free_flight();
  }
  last_stats_ = KernelStats{};
  // choose the contact model once per step, outside the particle loop
  if (!s_.contacts) return;
  if (p_.rotation)
    compute_forces(p_, list_, SpringDashpot<true>{s_.contact}, kc_, force_rows_.data(), force_rows_.size(),
                   force_.data(), torque_.data(), last_stats_);
  else
    compute_forces(p_, list_, SpringDashpot<false>{s_.contact}, kc_, force_rows_.data(), force_rows_.size(),
                   force_.data(), nullptr, last_stats_);
}

void DemSystem::commit() {
  {
    ScopedPhase t(timers_, t_force_);
    with_drive([&](const auto& drive) {
      integrate(p_, force_.data(), torque_.data(), drive, kc_, integrate_.data(), integrate_.size(),
                force_rows_.data(), force_rows_.size(), anchor_.data(), last_stats_);
    });
  }
  const double time_s = static_cast<double>(step_) * s_.dt_s;
  ++step_;
  // one reduction per step: max speed (a non-finite one is a blow-up), max overlap, blow-up flag, and
  // whether a particle has left its anchor's reach (the list is then rebuilt before the next step)
  double local[4] = {std::isfinite(last_stats_.max_speed2) ? last_stats_.max_speed2 : HUGE_VAL,
                     last_stats_.max_overlap, last_stats_.bad_particle >= 0 ? 1.0 : 0.0,
                     last_stats_.left_reach ? 1.0 : 0.0};
  double global[4];
  {
    ScopedPhase t(timers_, t_comm_);
    MPI_Allreduce(local, global, 4, MPI_DOUBLE, MPI_MAX, slabs_.comm());
  }
  const double overlap_rel = global[1] / s_.diameter_m;
  last_max_overlap_rel_ = overlap_rel;
  if (global[2] > 0 || !std::isfinite(global[0]) || overlap_rel > s_.overlap_limit) {
    // Name the particle(s) and the moment; every rank throws the same message.
    std::int64_t ids[3] = {last_stats_.bad_particle, -1, -1};
    struct {
      double value;
      int rank;
    } mine{last_stats_.max_overlap, slabs_.rank()}, top{};
    MPI_Allreduce(&mine, &top, 1, MPI_DOUBLE_INT, MPI_MAXLOC, slabs_.comm());
    std::int64_t pair[2] = {last_stats_.overlap_particle, last_stats_.overlap_partner};
    MPI_Bcast(pair, 2, MPI_INT64_T, top.rank, slabs_.comm());
    MPI_Allreduce(MPI_IN_PLACE, ids, 1, MPI_INT64_T, MPI_MAX, slabs_.comm());
    std::ostringstream msg;
    msg << "numerical blow-up at step " << step_ - 1 << " (t = " << time_s << " s): ";
    if (ids[0] >= 0)
      msg << "non-finite velocity of particle " << ids[0];
    else
      msg << "overlap of " << 100.0 * overlap_rel << " % of the diameter between particles " << pair[0] << " and "
          << pair[1] << " (limit " << 100.0 * s_.overlap_limit
          << " %): contacts too soft for the impact speeds, or the time step too large for them";
    throw RunError(msg.str());
  }
  if (global[3] > 0) rebuild_due_ = true;
}

Diagnostics DemSystem::diagnostics(bool synchronous) const {
  catch_up();
  const std::vector<double> v_later = synchronous ? next_velocity() : p_.v;
  const std::vector<double> w_later = synchronous ? next_angular_velocity() : p_.w;
  Diagnostics d;
  const double m = s_.mass_kg, inertia = 1.0 / kc_.inv_inertia;
  double sums[17] = {0};
  for (std::size_t i = 0; i < p_.n_owned; ++i) {
    double vn[3], xn[3];
    for (int c = 0; c < 3; ++c) {
      vn[c] = 0.5 * (p_.v[3 * i + c] + v_later[3 * i + c]);
      xn[c] = p_.x[3 * i + c];
    }
    sums[0] += 0.5 * m * (vn[0] * vn[0] + vn[1] * vn[1] + vn[2] * vn[2]);
    for (int c = 0; c < 3; ++c) sums[3 + c] += m * vn[c];
    sums[9] += m * (xn[1] * vn[2] - xn[2] * vn[1]);
    sums[10] += m * (xn[2] * vn[0] - xn[0] * vn[2]);
    sums[11] += m * (xn[0] * vn[1] - xn[1] * vn[0]);
    if (p_.rotation) {
      double wn[3];
      for (int c = 0; c < 3; ++c) wn[c] = 0.5 * (p_.w[3 * i + c] + w_later[3 * i + c]);
      sums[1] += 0.5 * inertia * (wn[0] * wn[0] + wn[1] * wn[1] + wn[2] * wn[2]);
      for (int c = 0; c < 3; ++c) sums[6 + c] += inertia * wn[c];
    }
    if (s_.contacts && list_valid_) {  // before the first step (or after a restart) there is no list yet
      for (std::int64_t e = list_.offset[i]; e < list_.offset[i + 1]; ++e) {
        const std::int32_t j = list_.partner(static_cast<std::size_t>(e));
        double r2 = 0;
        for (int c = 0; c < 3; ++c) {
          const double dx = xn[c] - p_.x[3 * j + c];
          r2 += dx * dx;
        }
        const double overlap = s_.diameter_m - std::sqrt(r2);
        if (overlap <= 0) continue;
        // each pair appears twice in the full list: half of each pair's energy per entry
        sums[2] += 0.25 * s_.contact.k_n * overlap * overlap;
        if (p_.rotation) {
          const double* xi = &list_.xi[3 * e];
          sums[2] += 0.25 * s_.contact.k_t * (xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2]);
        }
        sums[12] += 0.5;
        sums[13] = std::max(sums[13], overlap);
      }
    }
  }
  const double local_max = sums[13];
  sums[13] = 0;
  sums[14] = static_cast<double>(p_.n_owned);
  double global[17];
  MPI_Allreduce(sums, global, 17, MPI_DOUBLE, MPI_SUM, slabs_.comm());
  double global_max = 0;
  MPI_Allreduce(&local_max, &global_max, 1, MPI_DOUBLE, MPI_MAX, slabs_.comm());
  d.kinetic_translational_J = global[0];
  d.kinetic_rotational_J = global[1];
  d.contact_energy_J = global[2];
  d.particles = static_cast<std::int64_t>(global[14]);
  const double total_mass = m * static_cast<double>(d.particles);
  for (int c = 0; c < 3; ++c) {
    d.momentum[c] = global[3 + c];
    d.velocity_mean[c] = d.particles > 0 ? global[3 + c] / total_mass : 0.0;
    d.angular_momentum_spin[c] = global[6 + c];
    d.angular_momentum_orbital[c] = global[9 + c];
  }
  d.contacts = global[12];
  d.max_overlap_rel = global_max / s_.diameter_m;
  return d;
}

std::vector<double> DemSystem::next_velocity() const {
  catch_up();
  std::vector<double> out(3 * p_.n_owned);
  const V3 zero{0, 0, 0};
  with_drive([&](const auto& drive) {
    std::size_t r = 0;  // forces are stored per row (force_rows_, increasing)
    for (std::size_t i = 0; i < p_.n_owned; ++i) {
      const bool has_force = r < force_rows_.size() && static_cast<std::size_t>(force_rows_[r]) == i;
      store3(&out[3 * i], kicked_velocity(i, load3(&p_.v[3 * i]), has_force ? load3(&force_[3 * r]) : zero, drive, kc_));
      r += has_force;
    }
  });
  return out;
}

std::vector<double> DemSystem::next_angular_velocity() const {
  std::vector<double> out;
  if (!p_.rotation) return out;
  catch_up();
  out.resize(3 * p_.n_owned);
  const V3 zero{0, 0, 0};
  std::size_t r = 0;  // torques are stored per row (force_rows_, increasing)
  for (std::size_t i = 0; i < p_.n_owned; ++i) {
    const bool has_force = r < force_rows_.size() && static_cast<std::size_t>(force_rows_[r]) == i;
    store3(&out[3 * i], kicked_spin(load3(&p_.w[3 * i]), has_force ? load3(&torque_[3 * r]) : zero, kc_));
    r += has_force;
  }
  return out;
}

std::vector<double> DemSystem::synchronous_velocity() const {
  std::vector<double> out = next_velocity();
  for (std::size_t k = 0; k < out.size(); ++k) out[k] = 0.5 * (p_.v[k] + out[k]);
  return out;
}

std::vector<double> DemSystem::synchronous_angular_velocity() const {
  std::vector<double> out = next_angular_velocity();
  for (std::size_t k = 0; k < out.size(); ++k) out[k] = 0.5 * (p_.w[k] + out[k]);
  return out;
}

ContactStore DemSystem::contact_store() const {
  if (!list_valid_ || !p_.rotation) return store_;
  ContactStore s;
  list_.save_history(p_, s);
  return s;
}

std::size_t DemSystem::bytes() const {
  return p_.bytes() + list_.bytes() + (force_.capacity() + torque_.capacity()) * sizeof(double) +
         (force_rows_.capacity() + integrate_.capacity() + dormant_.capacity()) * sizeof(std::int32_t) +
         referenced_.capacity() +
         (store_.offset.capacity() + store_.partner.capacity()) * sizeof(std::int64_t) +
         store_.xi.capacity() * sizeof(double);
}

}  // namespace cgd::dem
