#include "sim/dem/comm.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "core/error.hpp"

namespace cgd::dem {

SlabDecomposition::SlabDecomposition(MPI_Comm comm, std::array<double, 3> box_m) : comm_(comm), box_(box_m) {
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &size_);
  for (int r = 0; r < size_; ++r) lower_.push_back(box_[1] * r / size_);
}

SlabDecomposition::SlabDecomposition(MPI_Comm comm, std::array<double, 3> box_m, const std::vector<double>& lower_bounds)
    : comm_(comm), box_(box_m) {
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &size_);
  set_lower_bounds(lower_bounds);
}

void SlabDecomposition::set_lower_bounds(const std::vector<double>& lower_bounds) {
  if (static_cast<int>(lower_bounds.size()) != size_ || lower_bounds.front() != 0.0)
    throw RunError("slab bounds: need one lower bound per rank, the first at y = 0");
  for (int r = 1; r < size_; ++r)
    if (!(lower_bounds[r] > lower_bounds[r - 1]) || !(lower_bounds[r] < box_[1]))
      throw RunError("slab bounds must increase within the box");
  lower_ = lower_bounds;
}

double SlabDecomposition::thinnest() const {
  double t = box_[1];
  for (int r = 0; r < size_; ++r) t = std::min(t, slab_lo(r + 1) - slab_lo(r));
  return t;
}

int SlabDecomposition::owner(double y) const {
  int r = static_cast<int>(std::floor(y / box_[1] * size_));
  r = std::min(std::max(r, 0), size_ - 1);
  while (r > 0 && y < slab_lo(r)) --r;
  while (r < size_ - 1 && y >= slab_lo(r + 1)) ++r;
  return r;
}

void SlabDecomposition::wrap(double* x) const {
  for (int d = 0; d < 3; ++d) {
    const double L = box_[d];
    if (x[d] < 0.0 || x[d] >= L) {
      x[d] -= L * std::floor(x[d] / L);
      if (x[d] >= L) x[d] = 0.0;  // -tiny + L rounds to L
    }
  }
}

namespace {
// Bit-exact transport of an int64 inside a double buffer.
double bits_to_double(std::int64_t i) {
  double d;
  std::memcpy(&d, &i, sizeof d);
  return d;
}
std::int64_t double_to_bits(double d) {
  std::int64_t i;
  std::memcpy(&i, &d, sizeof i);
  return i;
}
/// A ghost whose source is on this rank (a local swap): ghost g = particle i shifted by the periodic image,
/// the same arithmetic as pack_one followed by unpack_one.
inline void copy_local_ghost(Particles& p, const std::array<double, 3>& shift, std::size_t g, std::size_t i) {
  p.x[3 * g] = p.x[3 * i] + shift[0];
  p.x[3 * g + 1] = p.x[3 * i + 1] + shift[1];
  p.x[3 * g + 2] = p.x[3 * i + 2] + shift[2];
  p.v[3 * g] = p.v[3 * i];
  p.v[3 * g + 1] = p.v[3 * i + 1];
  p.v[3 * g + 2] = p.v[3 * i + 2];
  if (p.rotation) {
    p.w[3 * g] = p.w[3 * i];
    p.w[3 * g + 1] = p.w[3 * i + 1];
    p.w[3 * g + 2] = p.w[3 * i + 2];
  }
}
/// Ghost g from one received forward record (pack_one's layout).
inline void unpack_one(Particles& p, std::size_t g, const double* in) {
  std::memcpy(&p.x[3 * g], in, 3 * sizeof(double));
  std::memcpy(&p.v[3 * g], in + 3, 3 * sizeof(double));
  if (p.rotation) std::memcpy(&p.w[3 * g], in + 6, 3 * sizeof(double));
}
/// One particle's forward record: position shifted by the swap's periodic image, velocity, and the angular
/// velocity when rotation is simulated (6 or 9 doubles).
inline void pack_one(const Particles& p, std::int32_t i, const std::array<double, 3>& shift, double* out) {
  const double* xi = &p.x[3 * i];
  const double* vi = &p.v[3 * i];
  out[0] = xi[0] + shift[0];
  out[1] = xi[1] + shift[1];
  out[2] = xi[2] + shift[2];
  out[3] = vi[0];
  out[4] = vi[1];
  out[5] = vi[2];
  if (p.rotation) {
    const double* wi = &p.w[3 * i];
    out[6] = wi[0];
    out[7] = wi[1];
    out[8] = wi[2];
  }
}
}  // namespace

void GhostExchange::pack(const Particles& p, const Swap& s, std::vector<double>& buf) const {
  const int per = p.rotation ? 9 : 6;
  buf.resize(s.send.size() * per);
  double* out = buf.data();
  for (std::int32_t i : s.send) {
    pack_one(p, i, s.shift, out);
    out += per;
  }
}

void GhostExchange::pack_live(const Particles& p, const Swap& s, std::vector<double>& buf) const {
  const int per = p.rotation ? 9 : 6;
  buf.resize(s.live_send.size() * per);
  double* out = buf.data();
  for (std::int32_t k : s.live_send) {
    const std::int32_t i = s.send[k];
    pack_one(p, i, s.shift, out);
    out += per;
  }
}

void GhostExchange::restrict_forward(std::vector<char>& flag) {
  std::vector<char> out, in;
  for (std::size_t n = swaps_.size(); n-- > 0;) {
    Swap& s = swaps_[n];
    // my ghosts of this swap that are flagged (receiver's view)
    s.live_recv.clear();
    for (std::size_t k = 0; k < s.recv_count; ++k)
      if (flag[s.recv_first + k]) s.live_recv.push_back(static_cast<std::int32_t>(k));
    const char* theirs = nullptr;  // the flags of the ghosts my send list made, one per entry
    if (s.local) {
      theirs = flag.data() + s.recv_first;
    } else {
      // the flags go back the way the ghosts came: to peer_recv (who sent me these ghosts), and
      // from peer_send (to whom I sent mine)
      out.assign(flag.begin() + static_cast<std::ptrdiff_t>(s.recv_first),
                 flag.begin() + static_cast<std::ptrdiff_t>(s.recv_first + s.recv_count));
      in.assign(s.send.size(), 0);
      MPI_Sendrecv(out.data(), static_cast<int>(out.size()), MPI_CHAR, s.peer_recv, 80 + static_cast<int>(n), in.data(),
                   static_cast<int>(in.size()), MPI_CHAR, s.peer_send, 80 + static_cast<int>(n), slabs_.comm(),
                   MPI_STATUS_IGNORE);
      theirs = in.data();
    }
    s.live_send.clear();
    for (std::size_t k = 0; k < s.send.size(); ++k)
      if (theirs[k]) {
        s.live_send.push_back(static_cast<std::int32_t>(k));
        flag[static_cast<std::size_t>(s.send[k])] = 1;
      }
  }
  restricted_ = true;
}

void GhostExchange::build(Particles& p, double cutoff) {
  swaps_.clear();
  restricted_ = false;
  p.resize(p.n_owned, p.n_owned);
  // Reserve room for the ghosts up front: the ghost shell's share of the particles (faces of width
  // `cutoff` around the slab, 25 % margin) or 25 % more than last time, whichever is larger.
  {
    const auto& L = slabs_.box();
    const double slab = slabs_.y_hi() - slabs_.y_lo();
    const double shell = (1 + 2 * cutoff / L[0]) * (1 + 2 * cutoff / L[2]) * (1 + 2 * cutoff / slab) - 1;
    const double estimate = 1.25 * std::max(shell * static_cast<double>(p.n_owned), static_cast<double>(ghosts_));
    p.reserve(p.n_owned + static_cast<std::size_t>(estimate) + 64);
  }
  const int rank = slabs_.rank(), size = slabs_.size();
  for (int dim : {0, 2, 1}) {
    const std::size_t candidates = p.n_total;
    const bool decomposed = (dim == 1 && size > 1);
    const double L = slabs_.box()[dim];
    const double lo = dim == 1 ? slabs_.y_lo() : 0.0;
    const double hi = dim == 1 ? slabs_.y_hi() : L;
    for (int dir : {-1, +1}) {
      Swap s;
      s.dim = dim;
      s.local = !decomposed;
      // dir -1: particles near the lower face go to the lower neighbour, which sees them beyond its
      // upper face; crossing y = 0 (or x, z = 0) adds +L. dir +1 mirrors it.
      s.peer_send = decomposed ? (dir < 0 ? slabs_.down() : slabs_.up()) : rank;
      s.peer_recv = decomposed ? (dir < 0 ? slabs_.up() : slabs_.down()) : rank;
      const bool crosses = !decomposed || (dir < 0 ? rank == 0 : rank == size - 1);
      if (crosses) s.shift[dim] = dir < 0 ? L : -L;
      for (std::size_t i = 0; i < candidates; ++i) {
        const double c = p.x[3 * i + dim];
        if (dir < 0 ? c < lo + cutoff : c >= hi - cutoff) s.send.push_back(static_cast<std::int32_t>(i));
      }
      // exchange counts, then ids and kinematics
      std::int64_t n_send = static_cast<std::int64_t>(s.send.size()), n_recv = n_send;
      if (!s.local)
        MPI_Sendrecv(&n_send, 1, MPI_INT64_T, s.peer_send, 10 + dir, &n_recv, 1, MPI_INT64_T, s.peer_recv, 10 + dir,
                     slabs_.comm(), MPI_STATUS_IGNORE);
      s.recv_first = p.n_total;
      s.recv_count = static_cast<std::size_t>(n_recv);
      std::vector<std::int64_t> ids_send(s.send.size()), ids_recv(s.recv_count);
      for (std::size_t k = 0; k < s.send.size(); ++k) ids_send[k] = p.id[s.send[k]];
      if (s.local) {
        ids_recv = ids_send;
      } else {
        MPI_Sendrecv(ids_send.data(), static_cast<int>(ids_send.size()), MPI_INT64_T, s.peer_send, 20 + dir,
                     ids_recv.data(), static_cast<int>(ids_recv.size()), MPI_INT64_T, s.peer_recv, 20 + dir,
                     slabs_.comm(), MPI_STATUS_IGNORE);
      }
      p.resize(p.n_owned, p.n_total + s.recv_count);
      std::copy(ids_recv.begin(), ids_recv.end(), p.id.begin() + static_cast<std::ptrdiff_t>(s.recv_first));
      swaps_.push_back(std::move(s));
      // fill positions of this swap now: later swaps take these ghosts as candidates
      Swap& last = swaps_.back();
      pack(p, last, send_buf_);
      const int per = p.rotation ? 9 : 6;
      const double* in = send_buf_.data();
      if (!last.local) {
        recv_buf_.resize(last.recv_count * per);
        MPI_Sendrecv(send_buf_.data(), static_cast<int>(send_buf_.size()), MPI_DOUBLE, last.peer_send, 30 + dir,
                     recv_buf_.data(), static_cast<int>(recv_buf_.size()), MPI_DOUBLE, last.peer_recv, 30 + dir,
                     slabs_.comm(), MPI_STATUS_IGNORE);
        in = recv_buf_.data();
      }
      for (std::size_t k = 0; k < last.recv_count; ++k, in += per) {
        const std::size_t g = last.recv_first + k;
        unpack_one(p, g, in);
      }
    }
  }
  ghosts_ = p.n_total - p.n_owned;
}

void GhostExchange::forward(Particles& p) {
  const int per = p.rotation ? 9 : 6;
  if (restricted_) {
    for (const Swap& s : swaps_) {
      if (s.local) {
        for (std::int32_t k : s.live_recv) {
          const std::size_t g = s.recv_first + static_cast<std::size_t>(k), i = static_cast<std::size_t>(s.send[k]);
          copy_local_ghost(p, s.shift, g, i);
        }
        continue;
      }
      pack_live(p, s, send_buf_);
      recv_buf_.resize(s.live_recv.size() * per);
      MPI_Sendrecv(send_buf_.data(), static_cast<int>(send_buf_.size()), MPI_DOUBLE, s.peer_send, 40 + s.dim,
                   recv_buf_.data(), static_cast<int>(recv_buf_.size()), MPI_DOUBLE, s.peer_recv, 40 + s.dim,
                   slabs_.comm(), MPI_STATUS_IGNORE);
      const double* in = recv_buf_.data();
      for (std::int32_t k : s.live_recv) {
        const std::size_t g = s.recv_first + static_cast<std::size_t>(k);
        unpack_one(p, g, in);
        in += per;
      }
    }
    return;
  }
  for (const Swap& s : swaps_) {
    if (s.local) {
      // direct copy: ghost k is source s.send[k] shifted
      for (std::size_t k = 0; k < s.recv_count; ++k) {
        const std::size_t g = s.recv_first + k, i = static_cast<std::size_t>(s.send[k]);
        copy_local_ghost(p, s.shift, g, i);
      }
      continue;
    }
    pack(p, s, send_buf_);
    recv_buf_.resize(s.recv_count * per);
    MPI_Sendrecv(send_buf_.data(), static_cast<int>(send_buf_.size()), MPI_DOUBLE, s.peer_send, 40 + s.dim,
                 recv_buf_.data(), static_cast<int>(recv_buf_.size()), MPI_DOUBLE, s.peer_recv, 40 + s.dim,
                 slabs_.comm(), MPI_STATUS_IGNORE);
    const double* in = recv_buf_.data();
    for (std::size_t k = 0; k < s.recv_count; ++k, in += per) {
      const std::size_t g = s.recv_first + k;
      unpack_one(p, g, in);
    }
  }
}

void GhostExchange::migrate(Particles& p, ContactStore& store) {
  p.resize(p.n_owned, p.n_owned);
  if (slabs_.size() == 1) return;
  for (;;) {
    int leaving = 0;
    for (std::size_t i = 0; i < p.n_owned && !leaving; ++i)
      if (slabs_.owner(p.x[3 * i + 1]) != slabs_.rank()) leaving = 1;
    MPI_Allreduce(MPI_IN_PLACE, &leaving, 1, MPI_INT, MPI_MAX, slabs_.comm());
    if (!leaving) return;
    migrate_hop(p, store);
  }
}

void GhostExchange::migrate_hop(Particles& p, ContactStore& store) {
  const int size = slabs_.size();
  const int rank = slabs_.rank();
  const bool track_contacts = store.offset.size() == p.n_owned + 1;
  const int per = p.rotation ? 9 : 6;
  // Pack leavers per destination; keep the rest in order.
  std::vector<double> out_down, out_up;
  std::size_t kept = 0;
  ContactStore kept_store;
  for (std::size_t i = 0; i < p.n_owned; ++i) {
    const int dest = slabs_.owner(p.x[3 * i + 1]);
    const std::int64_t c0 = track_contacts ? store.offset[i] : 0, c1 = track_contacts ? store.offset[i + 1] : 0;
    if (dest == rank) {
      if (kept != i) {
        p.id[kept] = p.id[i];
        std::memcpy(&p.x[3 * kept], &p.x[3 * i], 3 * sizeof(double));
        std::memcpy(&p.v[3 * kept], &p.v[3 * i], 3 * sizeof(double));
        if (p.rotation) std::memcpy(&p.w[3 * kept], &p.w[3 * i], 3 * sizeof(double));
        if (p.external) std::memcpy(&p.a_ext[3 * kept], &p.a_ext[3 * i], 3 * sizeof(double));
      }
      ++kept;
      if (track_contacts) {
        for (std::int64_t k = c0; k < c1; ++k) {
          kept_store.partner.push_back(store.partner[k]);
          kept_store.xi.insert(kept_store.xi.end(), &store.xi[3 * k], &store.xi[3 * k + 3]);
        }
        kept_store.offset.push_back(static_cast<std::int64_t>(kept_store.partner.size()));
      }
      continue;
    }
    // one slab toward the owner, the shorter way round the ring (up when dest is at most size/2 above)
    const bool upward = (dest - rank + size) % size <= size / 2;
    std::vector<double>& out = upward ? out_up : out_down;
    out.push_back(bits_to_double(p.id[i]));
    out.insert(out.end(), &p.x[3 * i], &p.x[3 * i + 3]);
    out.insert(out.end(), &p.v[3 * i], &p.v[3 * i + 3]);
    if (p.rotation) out.insert(out.end(), &p.w[3 * i], &p.w[3 * i + 3]);
    if (p.external) out.insert(out.end(), &p.a_ext[3 * i], &p.a_ext[3 * i + 3]);
    out.push_back(static_cast<double>(c1 - c0));
    for (std::int64_t k = c0; k < c1; ++k) {
      out.push_back(bits_to_double(store.partner[k]));
      out.insert(out.end(), &store.xi[3 * k], &store.xi[3 * k + 3]);
    }
  }
  p.resize(kept, kept);
  if (track_contacts) store = std::move(kept_store);
  // Two rounds: send down / receive from up, then send up / receive from down. With two ranks
  // down == up, and everything leaving goes in the first round.
  const bool same_neighbour = slabs_.down() == slabs_.up();
  if (same_neighbour) {
    out_down.insert(out_down.end(), out_up.begin(), out_up.end());
    out_up.clear();
  }
  for (int round = 0; round < (same_neighbour ? 1 : 2); ++round) {
    std::vector<double>& out = round == 0 ? out_down : out_up;
    const int to = round == 0 ? slabs_.down() : slabs_.up();
    const int from = round == 0 ? slabs_.up() : slabs_.down();
    std::int64_t n_out = static_cast<std::int64_t>(out.size()), n_in = 0;
    MPI_Sendrecv(&n_out, 1, MPI_INT64_T, to, 50 + round, &n_in, 1, MPI_INT64_T, from, 50 + round, slabs_.comm(),
                 MPI_STATUS_IGNORE);
    std::vector<double> in(static_cast<std::size_t>(n_in));
    MPI_Sendrecv(out.data(), static_cast<int>(n_out), MPI_DOUBLE, to, 60 + round, in.data(), static_cast<int>(n_in),
                 MPI_DOUBLE, from, 60 + round, slabs_.comm(), MPI_STATUS_IGNORE);
    std::size_t pos = 0;
    while (pos < in.size()) {
      const std::size_t i = p.n_owned;
      p.resize(i + 1, i + 1);
      p.id[i] = double_to_bits(in[pos++]);
      std::memcpy(&p.x[3 * i], &in[pos], 3 * sizeof(double));
      std::memcpy(&p.v[3 * i], &in[pos + 3], 3 * sizeof(double));
      if (p.rotation) std::memcpy(&p.w[3 * i], &in[pos + 6], 3 * sizeof(double));
      pos += per;
      if (p.external) {
        std::memcpy(&p.a_ext[3 * i], &in[pos], 3 * sizeof(double));
        pos += 3;
      }
      const auto nc = static_cast<std::int64_t>(in[pos++]);
      for (std::int64_t k = 0; k < nc; ++k) {
        store.partner.push_back(double_to_bits(in[pos]));
        store.xi.insert(store.xi.end(), &in[pos + 1], &in[pos + 4]);
        pos += 4;
      }
      if (track_contacts) store.offset.push_back(static_cast<std::int64_t>(store.partner.size()));
    }
  }
}

}  // namespace cgd::dem
