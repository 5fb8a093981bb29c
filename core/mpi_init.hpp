#pragma once
// cgd::init_mpi — MPI_Init for every cgd executable, tool and test (ARCHITECTURE.md "Errors and exit statuses").
//
// Open MPI 4.1's MPI-IO layer (OMPIO), which HDF5's MPI-IO driver uses, opens its shared-file-pointer
// component "sharedfp/sm" at every MPI_File_open. That component guards its state with a POSIX named
// semaphore called /dev/shm/sem.OMPIO_<file's base name>, shared by every process on the machine that
// opens a file of the same base name (every run writes checkpoint.h5.tmp), and it is neither unlinked
// nor released when a process is killed while holding it. A run killed at that moment (a timeout, a
// SIGKILL, the chaos test) leaves the semaphore at 0, and from then on every run on the machine hangs
// for ever in H5Fcreate of a checkpoint — no error, no timeout. cgd never uses shared file pointers
// (HDF5 does not either), so init_mpi excludes that component before MPI_Init reads the MCA parameters:
// OMPI_MCA_sharedfp=^sm, unless the user set OMPI_MCA_sharedfp themselves. The remaining components
// (lockedfile, individual) hold no state across processes that survives a kill.
// Regression test: tests/unit/mpi_init_test.cpp (a semaphore left locked does not hang a file create).
namespace cgd {

/// Sets the MPI environment described above, then MPI_Init(argc, argv).
void init_mpi(int* argc, char*** argv);

}  // namespace cgd
