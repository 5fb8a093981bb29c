#pragma once
// The shared command-line front of the cgd tools (README.md "Command lines", ARCHITECTURE.md "Errors and exit statuses").
//
// A tool's main is
//
//   int main(int argc, char** argv) {
//     cgd::init_mpi(&argc, &argv);                 // if the tool uses MPI (core/mpi_init.hpp)
//     const int status = cgd::run_tool([&] {
//       const auto options = cgd::parse_run_command_line(argc, argv, "cgd-generate", "Resolved CFD-DEM
//       runs"); const auto scene = cgd::load_scene(options.scene_path, options.overrides);   // before any
//       output
//       ...
//       return cgd::kExitOk;
//     });
//     MPI_Finalize();
//     return status;
//   }
//
// run_tool turns the error kinds into the exit statuses of README.md "Exit statuses": InputError -> 2 ("error: ..."),
// RunError -> 1 ("run failed: ..."), Interrupted -> 128 + signal ("run interrupted: ...": 130 for SIGINT,
// 143 for SIGTERM), a bad option -> 2 (CLI11's message), --help/--version -> 0.
// Under MPI only rank 0 prints.
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace cgd {

/// Options of the tools that run a scene (cgd-generate, cgd-coarse).
struct RunOptions {
  std::string scene_path;              // positional SCENE.toml
  std::vector<std::string> overrides;  // --set SECTION.KEY=VALUE, in the order given
  std::string output_dir;              // -o/--output; empty: the caller defaults it (default_run_directory)
  bool restart = false;                // --restart: continue from the run directory's checkpoint
  bool quiet = false;                  // --quiet: errors, warnings and the final summary only
  double progress_interval_s = 60;     // --progress-interval: wall seconds between batch progress lines
};

/// Thrown by the parsers below when the command line ends the program before any work: --help and
/// --version (status 0, text for stdout) or a bad option (status 2, text for stderr). run_tool
/// catches it; call the parsers inside run_tool.
class CommandLineExit : public std::exception {
 public:
  CommandLineExit(int status, std::string out_text, std::string err_text)
      : status_(status), out_text_(std::move(out_text)), err_text_(std::move(err_text)) {}
  int status() const { return status_; }
  const std::string& out_text() const { return out_text_; }
  const std::string& err_text() const { return err_text_; }
  const char* what() const noexcept override { return "command line ends the program"; }

 private:
  int status_;
  std::string out_text_, err_text_;
};

/// Parses `TOOL SCENE.toml [--set KEY=VALUE]... [-o DIR] [--restart] [--quiet] [--progress-interval S]` (plus --help,
/// --version). `add_options`, if given, adds tool-specific options (e.g. cgd-coarse's --model)
/// to the CLI11 app before parsing; the variables they bind must outlive the call.
RunOptions parse_run_command_line(int argc, char** argv, const std::string& tool_name,
                                  const std::string& description,
                                  const std::function<void(CLI::App&)>& add_options = {});

/// For tools with their own options (cgd-filter, cgd-fit): adds --version (core/version.hpp) and
/// parses; a bad option, --help or --version throws CommandLineExit.
void parse_command_line(CLI::App& app, int argc, char** argv, const std::string& tool_name);

/// The one check of an output file a tool is about to write (cgd-filter, cgd-fit, cgd-coarse --summarise): refused
/// (InputError, exit 2) when it is one of the tool's own inputs (even with --force: a tool never writes over what it
/// reads), when it exists and `force` is false, or when it is a directory.
void check_output_file(const std::string& output, bool force, const std::vector<std::string>& inputs = {});

/// "out/<stage>/<scene stem>", e.g. default_run_directory("generate", "data/scenes/dry_settling.toml").
std::string default_run_directory(const std::string& stage, const std::string& scene_path);

/// Runs a tool body and maps its errors to exit statuses (see the top of this file). Messages go
/// to stderr, on rank 0 only when MPI is initialised.
int run_tool(const std::function<int()>& body);

/// True on MPI rank 0, and when MPI is not initialised (single process).
bool is_output_rank();

}  // namespace cgd
