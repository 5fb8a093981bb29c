#pragma once
// The two error kinds every cgd tool distinguishes (README.md "Command lines", ARCHITECTURE.md "Errors and exit statuses"):
//   InputError   -> exit status 2: a bad scene, file or option; nothing has been written.
//   RunError     -> exit status 1: a run that failed (numerical blow-up, I/O failure) after it started.
//   Interrupted  -> exit status 128 + signal (130 for SIGINT, 143 for SIGTERM, the shell's convention): a
//                   run stopped by a signal after writing its checkpoint.
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

/// A run stopped by SIGINT or SIGTERM at a step boundary, after its checkpoint was written; the exit
/// status is 128 + the signal number, as a shell reports a process the signal ended.
class Interrupted : public RunError {
 public:
  Interrupted(const std::string& what, int signal_number) : RunError(what), signal_number_(signal_number) {}
  int signal_number() const { return signal_number_; }
  int exit_status() const { return 128 + signal_number_; }

 private:
  int signal_number_;
};

inline constexpr int kExitOk = 0;
inline constexpr int kExitRunFailed = 1;
inline constexpr int kExitBadInput = 2;

}  // namespace cgd
