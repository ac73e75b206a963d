// The documented exit codes of `tinsmith` (README, "Exit codes"). The mapping
// from tinsmith::ErrorKind lives here and nowhere else.
#pragma once

#include "core/base/error.hpp"

namespace tinsmith::cli {

enum ExitCode : int {
  kExitOk = 0,
  kExitCheckFailed = 1,     ///< `validate` ran and found the TIN broken
  kExitUsage = 2,           ///< bad arguments
  kExitInput = 3,           ///< bad or unreadable input data
  kExitGeometry = 4,        ///< input cannot make a valid triangulation
  kExitIo = 5,              ///< an output could not be written
  kExitNotImplemented = 6,  ///< the subcommand or option does not exist yet
  kExitInternal = 70,       ///< a bug in tinsmith (EX_SOFTWARE)
};

ExitCode exitCodeFor(ErrorKind kind);

/// Thrown by a command whose check ran to the end and failed (after it has
/// printed its findings): main() exits with kExitCheckFailed, printing nothing
/// more. Not a tinsmith::Error — nothing went wrong in running the check.
struct CheckFailed {};

}  // namespace tinsmith::cli
