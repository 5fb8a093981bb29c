// GoogleTest main for cgd: MPI is initialised once for the whole process; under mpirun only rank 0
// prints results, so a failure on any rank still fails the process (gtest's exit status).
#include <gtest/gtest.h>
#include <mpi.h>

#include "core/mpi_init.hpp"

int main(int argc, char** argv) {
  cgd::init_mpi(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  const int local = RUN_ALL_TESTS();
  int global = 0;
  MPI_Allreduce(&local, &global, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return global;
}
