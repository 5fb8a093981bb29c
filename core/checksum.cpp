// FNV-1a 64-bit file checksums (see checksum.hpp).
#include "core/checksum.hpp"

#include <cstdint>
#include <cstdio>
#include <fstream>

#include "core/error.hpp"

namespace cgd {

std::string file_checksum_fnv1a(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot read the file to compute its checksum");
  std::uint64_t hash = 0xcbf29ce484222325ULL;  // FNV-1a 64-bit offset basis 14695981039346656037
  char buf[1 << 16];
  while (in) {
    in.read(buf, sizeof buf);
    const std::streamsize got = in.gcount();
    for (std::streamsize i = 0; i < got; ++i) {
      hash ^= static_cast<unsigned char>(buf[i]);
      hash *= 0x100000001b3ULL;  // FNV 64-bit prime 1099511628211
    }
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(hash));
  return hex;
}

}  // namespace cgd
