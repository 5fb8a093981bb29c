#pragma once
// A run directory of cgd-generate / cgd-coarse (docs/schema-run.md "Run directory"): its snapshots in step
// order and whether the run completed (docs/schema-run.md). The files are read by core/schema/snapshot.hpp.
#include <cstdint>
#include <string>
#include <vector>

namespace cgd {

/// A run directory of cgd-generate/cgd-coarse: its snapshots in step order (snapshots/snap_<step>.h5;
/// temporary and diagnostic files are not snapshots) and whether the run completed (DONE marker).
struct RunDirectory {
  std::string path;
  std::vector<std::string> snapshot_files;
  std::vector<std::int64_t> steps;
  bool complete = false;
};
/// InputError if `path` is not a directory or holds no snapshots/ folder.
RunDirectory list_run_directory(const std::string& path);

}  // namespace cgd
