#pragma once
// The fluid's periodic uniform grid and this rank's slab of it (ARCHITECTURE.md "Parallel decomposition").
//
// Cells (i, j, k) along (x, y, z), y vertical. The slabs are FFTW-MPI's blocks of the first array
// dimension, which is y: fields are stored with y slowest, index (j, k, i), x fastest, so every rank's
// slab is one contiguous range of FFTW's real array and the pressure solver's FFT needs no copy in y.
// A rank owns cell rows j in [j0, j0 + ny_local), [y_lo, y_hi) = [j0 h_y, (j0 + ny_local) h_y). The particles'
// slabs are their own (balanced, sim/dem/system.hpp); the coupler works on the whole grid (sim/coupling/exchange.hpp).
//
// Storage of a field: (ny_local + 2 g) planes of nz * nx values; local row j runs from -g to
// ny_local + g - 1, rows outside [0, ny_local) being ghost copies of the neighbouring slabs
// (exchanged with MPI_Sendrecv, or a periodic copy on one rank). x and z are periodic by index
// arithmetic (wrapped neighbour tables), so there are no ghosts in x and z.
//
// Staggered (MAC) placement: a cell-centred field at (i, j, k) lives at ((i+1/2) h_x, (j+1/2) h_y,
// (k+1/2) h_z); velocity component d at (i, j, k) lives on the *lower* d-face of that cell, e.g. u_x
// at (i h_x, (j+1/2) h_y, (k+1/2) h_z).
#include <mpi.h>

#include <array>
#include <cstddef>
#include <initializer_list>
#include <vector>

namespace cgd::fluid {

/// A rank's rows of the grid along y: [j0, j0 + count).
struct SlabRows {
  int j0 = 0;
  int count = 0;
};

/// Calls f(i, i_plus, i_minus) for i = 0 .. n-1 with periodic neighbours. The ends are peeled off so
/// that the interior runs with i_plus = i + 1 and i_minus = i - 1: the compiler sees unit strides and
/// can vectorise the body (the hot loops of the fluid run along x this way).
template <class F>
inline void periodic_row(int n, F&& f) {
  if (n == 1) {
    f(0, 0, 0);
    return;
  }
  f(0, 1, n - 1);
  for (int i = 1; i < n - 1; ++i) f(i, i + 1, i - 1);
  f(n - 1, 0, n - 2);
}

class FluidGrid {
 public:
  /// Ghost width needed by the solver's stencils (the y-advection of u_y reads eps two rows away).
  static constexpr int kGhost = 2;

  /// `cells` = (n_x, n_y, n_z), `box_m` = box edges in m. Collective over `comm`. Throws InputError
  /// if a rank would own fewer than kGhost rows of y (n_y too small for the number of ranks).
  FluidGrid(MPI_Comm comm, std::array<int, 3> cells, std::array<double, 3> box_m);

  /// The y-rows FFTW-MPI gives this rank for an (n_y, n_z, n_x) real array (r2c, transposed output), before
  /// any grid exists.
  static SlabRows fftw_slab_rows(MPI_Comm comm, std::array<int, 3> cells);

  MPI_Comm comm() const { return comm_; }
  int rank() const { return rank_; }
  int ranks() const { return size_; }
  int up() const { return (rank_ + 1) % size_; }
  int down() const { return (rank_ + size_ - 1) % size_; }

  const std::array<int, 3>& cells() const { return cells_; }
  int nx() const { return cells_[0]; }
  int ny() const { return cells_[1]; }
  int nz() const { return cells_[2]; }
  int j0() const { return rows_.j0; }
  int ny_local() const { return rows_.count; }
  const std::array<double, 3>& box() const { return box_; }
  const std::array<double, 3>& spacing() const { return h_; }
  double cell_volume() const { return h_[0] * h_[1] * h_[2]; }
  long long cells_total() const { return 1LL * cells_[0] * cells_[1] * cells_[2]; }
  /// This slab's extent in y, m: [j0 h_y, (j0 + ny_local) h_y).
  double y_lo_m() const { return rows_.j0 * h_[1]; }
  double y_hi_m() const { return (rows_.j0 + rows_.count) * h_[1]; }

  /// Values in one y-plane (nz * nx) and in one field including ghosts.
  std::size_t plane() const { return plane_; }
  std::size_t storage_size() const { return plane_ * (rows_.count + 2 * kGhost); }
  /// Owned values are contiguous: [first_owned(), first_owned() + owned_size()).
  std::size_t first_owned() const { return plane_ * kGhost; }
  std::size_t owned_size() const { return plane_ * rows_.count; }
  /// Index of (i, j_local, k); i in [0, n_x), k in [0, n_z), j_local in [-kGhost, ny_local + kGhost).
  std::size_t index(int i, int j_local, int k) const {
    return static_cast<std::size_t>(j_local + kGhost) * plane_ + static_cast<std::size_t>(k) * cells_[0] + i;
  }
  /// Periodic neighbour tables: x_plus()[i] = (i + 1) mod n_x, etc.
  const std::vector<int>& x_plus() const { return xp_; }
  const std::vector<int>& x_minus() const { return xm_; }
  const std::vector<int>& z_plus() const { return zp_; }
  const std::vector<int>& z_minus() const { return zm_; }

  /// A zero-filled field of storage_size().
  std::vector<double> make_field(double value = 0.0) const {
    return std::vector<double>(storage_size(), value);
  }

  /// Fill the y-ghost planes [-width, 0) and [ny_local, ny_local + width) of each field from the
  /// neighbouring slabs (periodic in y). Collective; width <= kGhost.
  void exchange_ghosts(std::initializer_list<double*> fields, int width = kGhost) const;

  /// Sum / max over all ranks.
  double sum(double local) const;
  double max(double local) const;

 private:
  MPI_Comm comm_;
  int rank_ = 0, size_ = 1;
  std::array<int, 3> cells_;
  std::array<double, 3> box_, h_;
  SlabRows rows_;
  std::size_t plane_ = 0;
  std::vector<int> xp_, xm_, zp_, zm_;
  mutable std::vector<double> send_buf_, recv_buf_;
};

}  // namespace cgd::fluid
