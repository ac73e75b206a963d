// Handing freed heap memory back to the operating system between the big
// stages of a build.
#pragma once

namespace tinsmith::ingest {

/// Returns the free pages of the C heap to the system (glibc: malloc_trim(0);
/// elsewhere nothing). glibc keeps what a stage freed in its heap — blocks
/// smaller than its mmap threshold, which grows to 32 MB once a big block is
/// freed — so without this the memory of the read layers and of cleaning stays
/// resident through the triangulation, whose big arrays come from fresh
/// mappings and cannot reuse it. Costs a walk over the heap (milliseconds).
void releaseFreeMemory();

}  // namespace tinsmith::ingest
