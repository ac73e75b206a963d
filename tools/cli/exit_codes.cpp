#include "tools/cli/exit_codes.hpp"

namespace tinsmith::cli {

ExitCode exitCodeFor(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::Usage: return kExitUsage;
    case ErrorKind::Input: return kExitInput;
    case ErrorKind::Geometry: return kExitGeometry;
    case ErrorKind::Io: return kExitIo;
    case ErrorKind::NotImplemented: return kExitNotImplemented;
    case ErrorKind::Internal: return kExitInternal;
  }
  return kExitInternal;
}

}  // namespace tinsmith::cli
