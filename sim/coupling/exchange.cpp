#include "sim/coupling/exchange.hpp"

#include <algorithm>
#include <string>

#include "core/error.hpp"

namespace cgd::coupling {

RowOwners RowOwners::gather(MPI_Comm comm, int j0, int count) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  RowOwners r;
  r.j0.resize(static_cast<std::size_t>(size));
  r.count.resize(static_cast<std::size_t>(size));
  MPI_Allgather(&j0, 1, MPI_INT, r.j0.data(), 1, MPI_INT, comm);
  MPI_Allgather(&count, 1, MPI_INT, r.count.data(), 1, MPI_INT, comm);
  int next = 0;
  for (int q = 0; q < size; ++q) {
    if (r.j0[q] != next) throw RunError("coupling rows: rank " + std::to_string(q) + "'s rows do not follow rank " +
                                        std::to_string(q - 1) + "'s");
    next += r.count[q];
  }
  return r;
}

namespace {

/// The four blocks of `ghost` planes at the y ends of a field of `k` values per cell on the whole view: the ghost
/// planes below and above, and the owned rows they are periodic copies of (the top rows, the bottom rows).
struct EdgeBlocks {
  std::size_t size;  // doubles per block
  double *lower_ghosts, *upper_ghosts, *bottom_rows, *top_rows;
};

EdgeBlocks edge_blocks(const GridView& g, double* field, int k) {
  const std::size_t K = static_cast<std::size_t>(k);
  return {g.plane() * static_cast<std::size_t>(g.ghost) * K, field + K * g.index(0, -g.ghost, 0),
          field + K * g.index(0, g.ny_local, 0), field + K * g.index(0, 0, 0),
          field + K * g.index(0, g.ny_local - g.ghost, 0)};
}

/// Counts and displacements (in doubles, from row 0) of every rank's rows of a k-valued field.
void row_blocks(const GridView& g, const RowOwners& rows, int k, std::vector<int>& counts, std::vector<int>& displs) {
  const std::size_t per_row = g.plane() * static_cast<std::size_t>(k);
  counts.resize(rows.count.size());
  displs.resize(rows.count.size());
  for (std::size_t q = 0; q < rows.count.size(); ++q) {
    counts[q] = static_cast<int>(per_row * static_cast<std::size_t>(rows.count[q]));
    displs[q] = static_cast<int>(per_row * static_cast<std::size_t>(rows.j0[q]));
  }
}

}  // namespace

void fold_ghost_rows(const GridView& g, double* field, int k) {
  const EdgeBlocks e = edge_blocks(g, field, k);
  for (std::size_t m = 0; m < e.size; ++m) e.top_rows[m] += e.lower_ghosts[m];
  for (std::size_t m = 0; m < e.size; ++m) e.bottom_rows[m] += e.upper_ghosts[m];
  std::fill(e.lower_ghosts, e.lower_ghosts + e.size, 0.0);
  std::fill(e.upper_ghosts, e.upper_ghosts + e.size, 0.0);
}

void reduce_rows_to_owners(MPI_Comm comm, const GridView& g, const RowOwners& rows, double* field, int k) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  if (size == 1) return;
  std::vector<int> counts, displs;
  row_blocks(g, rows, k, counts, displs);
  double* first_row = field + static_cast<std::size_t>(k) * g.index(0, 0, 0);
  std::vector<double> mine(static_cast<std::size_t>(counts[rank]));
  MPI_Reduce_scatter(first_row, mine.data(), counts.data(), MPI_DOUBLE, MPI_SUM, comm);
  std::copy(mine.begin(), mine.end(), first_row + displs[rank]);
}

void gather_rows(MPI_Comm comm, const GridView& g, const RowOwners& rows, double* field, int k) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  if (size > 1) {
    std::vector<int> counts, displs;
    row_blocks(g, rows, k, counts, displs);
    double* first_row = field + static_cast<std::size_t>(k) * g.index(0, 0, 0);
    MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, first_row, counts.data(), displs.data(), MPI_DOUBLE, comm);
  }
  const EdgeBlocks e = edge_blocks(g, field, k);
  std::copy(e.top_rows, e.top_rows + e.size, e.lower_ghosts);
  std::copy(e.bottom_rows, e.bottom_rows + e.size, e.upper_ghosts);
}

}  // namespace cgd::coupling
