#include "sim/fluid/grid.hpp"

#include <fftw3-mpi.h>

#include <algorithm>
#include <cstring>
#include <string>

#include "core/error.hpp"

namespace cgd::fluid {

SlabRows FluidGrid::fftw_slab_rows(MPI_Comm comm, std::array<int, 3> cells) {
  fftw_mpi_init();  // idempotent; required before any fftw_mpi_* call
  ptrdiff_t n0 = 0, start0 = 0, n1 = 0, start1 = 0;
  // Same call as the pressure solver's plan: (n_y, n_z, n_x/2+1) complex, transposed output.
  fftw_mpi_local_size_3d_transposed(cells[1], cells[2], cells[0] / 2 + 1, comm, &n0, &start0, &n1, &start1);
  return {static_cast<int>(start0), static_cast<int>(n0)};
}

FluidGrid::FluidGrid(MPI_Comm comm, std::array<int, 3> cells, std::array<double, 3> box_m)
    : comm_(comm), cells_(cells), box_(box_m) {
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &size_);
  for (int d = 0; d < 3; ++d) {
    if (cells_[d] < 1) throw InputError("fluid grid: cells[" + std::to_string(d) + "] must be >= 1");
    if (!(box_[d] > 0.0)) throw InputError("fluid grid: box edge " + std::to_string(d) + " must be > 0");
    h_[d] = box_[d] / cells_[d];
  }
  rows_ = fftw_slab_rows(comm_, cells_);
  int fewest = rows_.count;
  MPI_Allreduce(MPI_IN_PLACE, &fewest, 1, MPI_INT, MPI_MIN, comm_);
  if (fewest < kGhost)
    throw InputError("fluid.cells: n_y = " + std::to_string(cells_[1]) + " gives some of the " +
                     std::to_string(size_) + " ranks fewer than " + std::to_string(kGhost) +
                     " rows of cells; use more cells in y or fewer ranks");
  plane_ = static_cast<std::size_t>(cells_[0]) * cells_[2];
  xp_.resize(cells_[0]);
  xm_.resize(cells_[0]);
  for (int i = 0; i < cells_[0]; ++i) {
    xp_[i] = (i + 1) % cells_[0];
    xm_[i] = (i + cells_[0] - 1) % cells_[0];
  }
  zp_.resize(cells_[2]);
  zm_.resize(cells_[2]);
  for (int k = 0; k < cells_[2]; ++k) {
    zp_[k] = (k + 1) % cells_[2];
    zm_[k] = (k + cells_[2] - 1) % cells_[2];
  }
}

void FluidGrid::exchange_ghosts(std::initializer_list<double*> fields, int width) const {
  width = std::min(width, kGhost);
  const std::size_t block = plane_ * width;  // values per field per side
  const int n = rows_.count;
  if (size_ == 1) {
    for (double* f : fields) {
      // lower ghosts [-w, 0) <- owned [n - w, n); upper ghosts [n, n + w) <- owned [0, w)
      std::memcpy(f + index(0, -width, 0), f + index(0, n - width, 0), block * sizeof(double));
      std::memcpy(f + index(0, n, 0), f + index(0, 0, 0), block * sizeof(double));
    }
    return;
  }
  const std::size_t total = block * fields.size();
  send_buf_.resize(total);
  recv_buf_.resize(total);
  // 1) my lowest owned rows go down; the rows above my slab come from up.
  std::size_t o = 0;
  for (double* f : fields) {
    std::memcpy(send_buf_.data() + o, f + index(0, 0, 0), block * sizeof(double));
    o += block;
  }
  MPI_Sendrecv(send_buf_.data(), static_cast<int>(total), MPI_DOUBLE, down(), 71, recv_buf_.data(),
               static_cast<int>(total), MPI_DOUBLE, up(), 71, comm_, MPI_STATUS_IGNORE);
  o = 0;
  for (double* f : fields) {
    std::memcpy(f + index(0, n, 0), recv_buf_.data() + o, block * sizeof(double));
    o += block;
  }
  // 2) my highest owned rows go up; the rows below my slab come from down.
  o = 0;
  for (double* f : fields) {
    std::memcpy(send_buf_.data() + o, f + index(0, n - width, 0), block * sizeof(double));
    o += block;
  }
  MPI_Sendrecv(send_buf_.data(), static_cast<int>(total), MPI_DOUBLE, up(), 72, recv_buf_.data(),
               static_cast<int>(total), MPI_DOUBLE, down(), 72, comm_, MPI_STATUS_IGNORE);
  o = 0;
  for (double* f : fields) {
    std::memcpy(f + index(0, -width, 0), recv_buf_.data() + o, block * sizeof(double));
    o += block;
  }
}

double FluidGrid::sum(double local) const {
  double global = 0.0;
  MPI_Allreduce(&local, &global, 1, MPI_DOUBLE, MPI_SUM, comm_);
  return global;
}

double FluidGrid::max(double local) const {
  double global = 0.0;
  MPI_Allreduce(&local, &global, 1, MPI_DOUBLE, MPI_MAX, comm_);
  return global;
}

}  // namespace cgd::fluid
