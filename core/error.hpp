#pragma once
// The two error kinds every cgd tool distinguishes (design.md, "Command lines"):
//   InputError   -> exit status 2: a bad scene, file or option; nothing has been written.
//   RunError     -> exit status 1: a run that failed (numerical blow-up, I/O failure) after it started.
#include <stdexcept>
#include <string>

namespace cgd {

/// Bad input: the message names the file, the key, the value given and what is allowed.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A run that failed after it started (NaN, overlap, CFL, I/O); the message says where and when.
class RunError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr int kExitOk = 0;
inline constexpr int kExitRunFailed = 1;
inline constexpr int kExitBadInput = 2;

}  // namespace cgd
