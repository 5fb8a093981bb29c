// FNV-1a 64-bit file checksums (see checksum.hpp).
#include "core/checksum.hpp"

#include <cstdio>
#include <fstream>
#include <vector>

#include "core/error.hpp"

namespace cgd {

std::string Fnv1a::hex() const {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(hash));
  return hex;
}

std::string file_checksum_fnv1a_from(const std::string& path, std::uint64_t offset, std::uint64_t* bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot read the file to compute its checksum");
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::uint64_t>(in.tellg());
  Fnv1a h;
  std::uint64_t count = 0;
  if (size > offset) {
    in.seekg(static_cast<std::streamoff>(offset));
    std::vector<char> buf(1 << 16);
    while (in) {
      in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
      const std::streamsize got = in.gcount();
      h.update(buf.data(), static_cast<std::size_t>(got));
      count += static_cast<std::uint64_t>(got);
    }
  }
  if (bytes) *bytes = count;
  return h.hex();
}

std::string file_checksum_fnv1a(const std::string& path) {
  return file_checksum_fnv1a_from(path, 0, nullptr);
}

}  // namespace cgd
