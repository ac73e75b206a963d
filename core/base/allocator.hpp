// Process-wide allocator setting for programs that build large meshes.
#pragma once

namespace tinsmith {

/// Makes every large block (>= 256 KiB) a separate mapping that goes back to
/// the system when freed. glibc otherwise raises its mapping threshold after
/// the first large free (up to 32 MiB), so the multi-megabyte temporaries of
/// a build end up in the heap and stay resident after they are freed, which
/// raises peak memory by tens of megabytes. The heap's top keeps up to
/// 8 MiB free and grows 8 MiB at a time (not 128 KiB, glibc's trim
/// threshold once the mapping threshold is set): a few MiB more at the peak
/// (each thread's arena may keep its 8 MiB) for 42 % fewer page faults and
/// a third less kernel CPU in a tiling run (docs/benchmarks.md). Call once
/// at program start, before any thread is created; a no-op on other C
/// libraries.
void returnLargeBlocksToSystem();

}  // namespace tinsmith
