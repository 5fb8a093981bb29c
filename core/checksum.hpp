#pragma once
// File checksums recorded in cgd's files (docs/schema-filtered.md: /snapshots checksums; the drag model's
// /sources; fluid.drag_model_checksum of a scene that uses a model file).
#include <string>

namespace cgd {

/// FNV-1a 64-bit hash (offset basis 14695981039346656037, prime 1099511628211) of a file's bytes, as 16
/// lowercase hex digits. InputError naming the file if it cannot be read.
std::string file_checksum_fnv1a(const std::string& path);

}  // namespace cgd
