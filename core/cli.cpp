// Shared command-line front of the cgd tools: CLI11 parsing and the exit-status contract.
#include "core/cli.hpp"

#include <mpi.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "core/error.hpp"
#include "core/version.hpp"

namespace cgd {

bool is_output_rank() {
  int initialized = 0, finalized = 0;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  if (!initialized || finalized) return true;
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank == 0;
}

void parse_command_line(CLI::App& app, int argc, char** argv, const std::string& tool_name) {
  app.set_version_flag("--version", tool_name + " " + code_version(), "Print the version and exit");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::ostringstream out, err;
    const int status = app.exit(e, out, err);
    // CLI11 reports help and version with status 0; every other parse error is bad input.
    throw CommandLineExit(status == 0 ? kExitOk : kExitBadInput, out.str(), err.str());
  }
}

RunOptions parse_run_command_line(int argc, char** argv, const std::string& tool_name,
                                  const std::string& description,
                                  const std::function<void(CLI::App&)>& add_options) {
  RunOptions options;
  CLI::App app{description, tool_name};
  app.add_option("scene", options.scene_path,
                 "Scene file (TOML), e.g. data/scenes/dry_settling.toml; with --restart -o DIR it may be left out "
                 "(DIR/scene.toml is used)")
      ->type_name("SCENE.toml");
  app.add_option("--set", options.overrides,
                 "Override one scene key, SECTION.KEY=VALUE with the value in TOML "
                 "(e.g. --set particles.solids_fraction=0.2); repeatable")
      ->type_name("KEY=VALUE")
      ->take_all()
      ->allow_extra_args(false);
  app.add_option("-o,--output", options.output_dir, "Run directory (default: out/<stage>/<scene name>)")
      ->type_name("DIR");
  app.add_flag("--restart", options.restart, "Continue from the checkpoint in the run directory");
  app.add_flag("--quiet", options.quiet, "Errors, warnings and the final summary only: no banner, no progress");
  app.add_option("--progress-interval", options.progress_interval_s,
                 "Wall seconds between progress lines when stderr is not a terminal (a batch log; default 60); "
                 "on a terminal one line is updated about once a second")
      ->type_name("SECONDS");
  if (add_options) add_options(app);
  parse_command_line(app, argc, argv, tool_name);
  if (!(options.progress_interval_s > 0) || !std::isfinite(options.progress_interval_s)) {
    std::ostringstream text;
    text << "--progress-interval: " << options.progress_interval_s
         << " is not allowed (wall seconds between progress lines, > 0)\nRun with --help for more information.\n";
    throw CommandLineExit(kExitBadInput, "", text.str());
  }
  if (options.scene_path.empty()) {
    if (!options.restart || options.output_dir.empty())
      throw CommandLineExit(kExitBadInput, "",
                            "scene is required (only --restart -o DIR may leave it out: the run's own "
                            "DIR/scene.toml is used)\nRun with --help for more information.\n");
    options.scene_path = (std::filesystem::path(options.output_dir) / "scene.toml").string();
  }
  return options;
}

std::string default_run_directory(const std::string& stage, const std::string& scene_path) {
  return (std::filesystem::path("out") / stage / std::filesystem::path(scene_path).stem()).string();
}

namespace {

/// An error thrown on some ranks only would leave the others waiting forever in their next collective
/// call. So a rank that catches an error first waits (on a communicator of its own, where no other
/// collective can be pending) for the other ranks to catch theirs: when every rank failed -- the usual
/// case, as checks that can differ between ranks are made collective -- they agree within moments and the
/// run ends normally with the status. When some rank has not failed within kAgreeSeconds it is stuck in a
/// collective (or still working): the failing rank prints its message, naming itself, and calls
/// MPI_Abort with the status, which ends every rank of the job (mpirun exits with that status).
constexpr double kAgreeSeconds = 5.0;
MPI_Comm g_error_comm = MPI_COMM_NULL;

bool mpi_active() {
  int initialized = 0, finalized = 0;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  return initialized && !finalized;
}

/// Returns when every rank has failed too; otherwise reports `text` from this rank and aborts the job.
void agree_or_abort(const std::string& text, int status) {
  if (!mpi_active() || g_error_comm == MPI_COMM_NULL) return;
  int size = 1, rank = 0;
  MPI_Comm_size(g_error_comm, &size);
  MPI_Comm_rank(g_error_comm, &rank);
  if (size == 1) return;
  MPI_Request request;
  MPI_Ibarrier(g_error_comm, &request);
  const double start = MPI_Wtime();
  int done = 0;
  while (!done && MPI_Wtime() - start < kAgreeSeconds) {
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (!done) usleep(1000);
  }
  if (done) return;
  std::cerr << "rank " << rank << " of " << size << ": " << text << "rank " << rank
            << ": the other ranks did not fail with it within " << kAgreeSeconds
            << " s (an error on some ranks only); aborting the job with exit status " << status << "\n"
            << std::flush;
  MPI_Abort(MPI_COMM_WORLD, status);
}

}  // namespace

int run_tool(const std::function<int()>& body) {
  if (mpi_active() && g_error_comm == MPI_COMM_NULL) MPI_Comm_dup(MPI_COMM_WORLD, &g_error_comm);
  const auto report = [](const std::string& text, int status) {
    agree_or_abort(text, status);
    if (is_output_rank()) std::cerr << text << std::flush;
    return status;
  };
  try {
    return body();
  } catch (const CommandLineExit& e) {
    if (is_output_rank()) {
      std::cout << e.out_text() << std::flush;
      std::cerr << e.err_text() << std::flush;
    }
    return e.status();
  } catch (const InputError& e) {
    return report(std::string("error: ") + e.what() + "\n", kExitBadInput);
  } catch (const Interrupted& e) {
    return report(std::string("run interrupted: ") + e.what() + "\n", e.exit_status());
  } catch (const RunError& e) {
    return report(std::string("run failed: ") + e.what() + "\n", kExitRunFailed);
  } catch (const std::exception& e) {
    return report(std::string("run failed (internal error): ") + e.what() + "\n", kExitRunFailed);
  }
}

void check_output_file(const std::string& output, bool force, const std::vector<std::string>& inputs) {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (const std::string& in : inputs)
    if (fs::exists(output, ec) && fs::equivalent(output, in, ec))
      throw InputError("-o " + output + ": it is one of the inputs (" + in + "); a tool never writes over its own input, "
                       "even with --force: give another output path");
  if (fs::is_directory(output, ec)) throw InputError("-o " + output + ": the output path is a directory");
  if (fs::exists(output, ec) && !force)
    throw InputError("-o " + output + ": the output file exists (give --force to overwrite it)");
}

}  // namespace cgd
