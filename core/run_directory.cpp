// A run directory's snapshots in step order (core/run_directory.hpp).
#include "core/run_directory.hpp"

#include <algorithm>
#include <filesystem>
#include <regex>
#include <utility>

#include "core/error.hpp"

namespace cgd {

namespace fs = std::filesystem;

RunDirectory list_run_directory(const std::string& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec))
    throw InputError(path + ": no such run directory (" + (fs::exists(path, ec) ? "not a directory" : "does not exist") + ")");
  const fs::path snaps = fs::path(path) / "snapshots";
  if (!fs::is_directory(snaps, ec))
    throw InputError(path + ": not a run directory (no snapshots/ folder; expected the output of cgd-generate -o DIR)");
  RunDirectory run;
  run.path = path;
  run.complete = fs::exists(fs::path(path) / "DONE", ec);
  static const std::regex name(R"(snap_(\d+)\.h5)");
  std::vector<std::pair<std::int64_t, std::string>> found;
  for (const auto& entry : fs::directory_iterator(snaps)) {
    std::smatch m;
    const std::string file = entry.path().filename().string();
    if (entry.is_regular_file() && std::regex_match(file, m, name))
      found.emplace_back(std::stoll(m[1].str()), entry.path().string());
  }
  std::sort(found.begin(), found.end());
  for (auto& [step, file] : found) {
    run.steps.push_back(step);
    run.snapshot_files.push_back(file);
  }
  return run;
}

}  // namespace cgd
