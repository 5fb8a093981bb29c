// cgd::init_mpi (core/mpi_init.hpp): a POSIX semaphore that Open MPI's OMPIO sharedfp/sm component left
// locked (its holder was killed) must not hang the next HDF5 file create of the same base name. Before
// init_mpi excluded that component, such a semaphore made every later checkpoint write of every run on
// the machine wait for ever (seen in CI: five e2e/stability tests timed out after the chaos-kill test).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <mpi.h>
#include <semaphore.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <string>
#include <thread>

#include "core/h5.hpp"
#include "temp_dir.hpp"

namespace {

TEST(MpiInit, StaleOmpioSemaphoreDoesNotHangFileCreate) {
  cgd::testing::TempDir dir("cgd_test_mpi_init");
  // The name OMPIO's sm component derives from a file's base name (Open MPI 4.1 sharedfp_sm_file_open.c).
  const std::string base = "stale_semaphore_" + std::to_string(getpid()) + ".h5";
  const std::string sem_name = "/OMPIO_" + base;
  sem_unlink(sem_name.c_str());
  sem_t* sem = sem_open(sem_name.c_str(), O_CREAT | O_EXCL, 0644, 0);  // value 0: as a killed holder leaves it
  ASSERT_NE(sem, SEM_FAILED) << "could not create the semaphore " << sem_name;

  // MPI stays on this thread; a watchdog releases the semaphore if the create is still waiting after 30 s
  // (an unloaded create takes milliseconds), so a regression fails the test instead of hanging the suite.
  std::atomic<bool> created{false};
  std::atomic<bool> released{false};
  std::thread watchdog([&] {
    for (int i = 0; i < 300 && !created.load(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (!created.load()) {
      released = true;
      sem_post(sem);
    }
  });
  { cgd::h5::File::create((dir.path() / base).string(), MPI_COMM_SELF); }
  created = true;
  watchdog.join();
  sem_close(sem);
  sem_unlink(sem_name.c_str());
  EXPECT_FALSE(released.load()) << "H5Fcreate of " << base << " waited on the stale semaphore " << sem_name
                                << " until the watchdog released it: OMPIO's sharedfp/sm is in use";
}

}  // namespace
