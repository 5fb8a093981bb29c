#pragma once
// Running a scene through the engine inside a test: run_scene with its stdout (banner, timing report)
// swallowed, so that test logs show only the tests' own output.
#include <mpi.h>

#include <filesystem>
#include <iostream>
#include <sstream>

#include "core/scene.hpp"
#include "sim/run.hpp"
#include "tests/unit/temp_dir.hpp"

namespace cgd::testing {

/// Runs `scene` into `output_dir` on `comm` (collective), quietly (`restart`: continued from the directory's
/// checkpoint, as --restart); exceptions propagate with std::cout restored.
inline void run_quietly(const Scene& scene, const std::filesystem::path& output_dir, MPI_Comm comm,
                        bool restart = false) {
  RunSettings rs;
  rs.output_dir = output_dir.string();
  rs.quiet = true;
  rs.restart = restart;
  std::ostringstream sink;
  std::streambuf* old = std::cout.rdbuf(sink.rdbuf());
  try {
    run_scene(scene, rs, comm);
  } catch (...) {
    std::cout.rdbuf(old);
    throw;
  }
  std::cout.rdbuf(old);
}

/// Runs `scene` on one rank into DIR/run and returns that run directory.
inline std::filesystem::path run_quietly(const Scene& scene, const TempDir& dir) {
  const std::filesystem::path run = dir / "run";
  run_quietly(scene, run, MPI_COMM_SELF);
  return run;
}

}  // namespace cgd::testing
