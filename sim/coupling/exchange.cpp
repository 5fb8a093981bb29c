#include "sim/coupling/exchange.hpp"

#include <algorithm>

namespace cgd::coupling {

void accumulate_ghosts(MPI_Comm comm, const GridView& g, std::initializer_list<double*> fields) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const int up = (rank + 1) % size, down = (rank + size - 1) % size;
  const std::size_t block = g.plane() * static_cast<std::size_t>(g.ghost);
  const std::size_t nf = fields.size();
  std::vector<double> send(block * nf), recv(block * nf);
  // Two rounds: lower ghosts -> down neighbour's top rows; upper ghosts -> up neighbour's bottom rows.
  for (int round = 0; round < 2; ++round) {
    const std::size_t ghost_first = round == 0 ? 0 : g.index(0, g.ny_local, 0);
    std::size_t f = 0;
    for (double* field : fields) {
      std::copy(field + ghost_first, field + ghost_first + block, send.begin() + static_cast<std::ptrdiff_t>(f * block));
      ++f;
    }
    const int to = round == 0 ? down : up, from = round == 0 ? up : down;
    if (size == 1) {
      recv = send;
    } else {
      MPI_Sendrecv(send.data(), static_cast<int>(send.size()), MPI_DOUBLE, to, 70 + round, recv.data(),
                   static_cast<int>(recv.size()), MPI_DOUBLE, from, 70 + round, comm, MPI_STATUS_IGNORE);
    }
    // received lower ghosts of `up` land on my top rows; received upper ghosts of `down` on my bottom rows
    const std::size_t dest = round == 0 ? g.index(0, g.ny_local - g.ghost, 0) : g.index(0, 0, 0);
    f = 0;
    for (double* field : fields) {
      const double* in = recv.data() + f * block;
      for (std::size_t k = 0; k < block; ++k) field[dest + k] += in[k];
      ++f;
    }
  }
  for (double* field : fields) {
    std::fill(field, field + block, 0.0);
    std::fill(field + g.index(0, g.ny_local, 0), field + g.index(0, g.ny_local, 0) + block, 0.0);
  }
}

void exchange_interleaved_ghosts(MPI_Comm comm, const GridView& g, double* field, int k) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const std::size_t K = static_cast<std::size_t>(k);
  const std::size_t block = g.plane() * static_cast<std::size_t>(g.ghost) * K;
  double* lower_ghosts = field + K * g.index(0, -g.ghost, 0);
  double* upper_ghosts = field + K * g.index(0, g.ny_local, 0);
  const double* bottom_rows = field + K * g.index(0, 0, 0);
  const double* top_rows = field + K * g.index(0, g.ny_local - g.ghost, 0);
  if (size == 1) {
    std::copy(top_rows, top_rows + block, lower_ghosts);
    std::copy(bottom_rows, bottom_rows + block, upper_ghosts);
    return;
  }
  const int up = (rank + 1) % size, down = (rank + size - 1) % size;
  // my bottom rows go down, the rows above my slab come from up; then the mirror
  MPI_Sendrecv(bottom_rows, static_cast<int>(block), MPI_DOUBLE, down, 73, upper_ghosts, static_cast<int>(block),
               MPI_DOUBLE, up, 73, comm, MPI_STATUS_IGNORE);
  MPI_Sendrecv(top_rows, static_cast<int>(block), MPI_DOUBLE, up, 74, lower_ghosts, static_cast<int>(block),
               MPI_DOUBLE, down, 74, comm, MPI_STATUS_IGNORE);
}

}  // namespace cgd::coupling
