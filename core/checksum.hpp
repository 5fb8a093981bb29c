#pragma once
// File checksums recorded in cgd's files (docs/schema-filtered.md: /snapshots checksums; the drag model's
// /sources; fluid.drag_model_checksum of a scene that uses a model file; the checksum seal of every file
// cgd writes, core/h5.hpp).
#include <cstddef>
#include <cstdint>
#include <string>

namespace cgd {

/// FNV-1a 64-bit hash (offset basis 14695981039346656037, prime 1099511628211), fed in pieces.
struct Fnv1a {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  void update(const char* data, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      hash ^= static_cast<unsigned char>(data[i]);
      hash *= 0x100000001b3ULL;
    }
  }
  std::string hex() const;  // 16 lowercase hex digits
};

/// FNV-1a 64-bit hash of a file's bytes, as 16 lowercase hex digits. InputError naming the file if it
/// cannot be read.
std::string file_checksum_fnv1a(const std::string& path);

/// FNV-1a 64-bit hash of the bytes of `path` from `offset` to its end, as 16 hex digits; `bytes` gets
/// their count (0 when the file is shorter than `offset`). InputError naming the file if it cannot be read.
std::string file_checksum_fnv1a_from(const std::string& path, std::uint64_t offset, std::uint64_t* bytes);

}  // namespace cgd
