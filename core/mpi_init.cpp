// cgd::init_mpi: see mpi_init.hpp for why OMPIO's sharedfp/sm component is excluded.
#include "core/mpi_init.hpp"

#include <mpi.h>

#include <cstdlib>

namespace cgd {

void init_mpi(int* argc, char*** argv) {
  // overwrite = 0: a user's own OMPI_MCA_sharedfp (or an MPI that is not Open MPI, which ignores it) wins.
  setenv("OMPI_MCA_sharedfp", "^sm", 0);
  MPI_Init(argc, argv);
}

}  // namespace cgd
