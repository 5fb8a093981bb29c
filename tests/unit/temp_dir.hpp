#pragma once
// A fresh directory for one test under the system's temporary directory (mkdtemp), removed when the
// object goes out of scope unless CGD_KEEP_TEST_FILES is set in the environment (then its path is
// printed, to look at the files a failing test wrote).
#include <stdlib.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace cgd::testing {

class TempDir {
 public:
  explicit TempDir(const std::string& prefix = "cgd_test") {
    std::string pattern = (std::filesystem::temp_directory_path() / (prefix + "_XXXXXX")).string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed for " + pattern);
    path_ = pattern;
  }
  ~TempDir() {
    if (std::getenv("CGD_KEEP_TEST_FILES")) {
      std::printf("kept test files in %s\n", path_.c_str());
      return;
    }
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

}  // namespace cgd::testing
