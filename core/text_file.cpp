#include "core/text_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "core/error.hpp"

namespace cgd {

namespace {

/// Writes `text` to `tmp` and fsyncs it; returns 0 or the errno of the first failure.
int write_synced(const std::string& tmp, const std::string& text) {
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) return errno;
  std::size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int error = errno;
      ::close(fd);
      return error;
    }
    written += static_cast<std::size_t>(n);
  }
  int error = ::fsync(fd) != 0 ? errno : 0;
  if (::close(fd) != 0 && error == 0) error = errno;
  return error;
}

}  // namespace

void write_text_files_atomically(const std::vector<std::pair<std::filesystem::path, std::string>>& files) {
  std::vector<std::string> tmps;
  auto fail = [&](const std::string& tmp, int error) {
    for (const std::string& t : tmps) std::remove(t.c_str());
    throw RunError(tmp + ": cannot write (" + std::strerror(error) + ")");
  };
  for (const auto& [path, text] : files) {
    tmps.push_back(path.string() + ".tmp");
    if (const int error = write_synced(tmps.back(), text); error != 0) fail(tmps.back(), error);
  }
  for (std::size_t i = 0; i < files.size(); ++i)
    if (std::rename(tmps[i].c_str(), files[i].first.c_str()) != 0) fail(tmps[i], errno);
}

void write_text_atomically(const std::filesystem::path& path, const std::string& text) {
  write_text_files_atomically({{path, text}});
}

}  // namespace cgd
