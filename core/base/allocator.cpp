#include "core/base/allocator.hpp"

#include <cstdlib>  // defines __GLIBC__ on glibc

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace tinsmith {

void returnLargeBlocksToSystem() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 256 * 1024);
  // The heap's own top: kept up to 8 MiB free before it is given back, and
  // grown 8 MiB at a time. Setting the threshold above turns off glibc's
  // dynamic trim threshold, leaving 128 KiB: every small-block churn at the
  // top went back to the system and was faulted in again: 567 k page
  // faults in a tiling run of SRTM N44W072, 327 k with these.
  mallopt(M_TRIM_THRESHOLD, 8 * 1024 * 1024);
  mallopt(M_TOP_PAD, 8 * 1024 * 1024);
#endif
}

}  // namespace tinsmith
