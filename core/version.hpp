#pragma once
// The code version written as `code_version` into every output file and printed by --version:
// "<project version>-<git describe --always --dirty --tags>", e.g. 0.1.0-d050234-dirty. Defined in a source
// file that cmake/code_version.cmake regenerates at every build (not at configure time only), so a binary
// built after a new commit names that commit.

namespace cgd {

const char* code_version();

}  // namespace cgd
