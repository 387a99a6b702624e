#pragma once

/// Process-wide settings both tools make at start-up.

namespace stereoscene::support {

/// Keeps freed memory in the process instead of returning it to the kernel (glibc's
/// `mallopt`: blocks up to 32 MiB come from the heap, the heap gives back only more than
/// 128 MiB free). Both tools allocate the same megabytes on every frame, and with glibc's
/// defaults (a dynamic mmap threshold, 128 KiB trimming) they came back as fresh pages, faulted
/// in again each frame: cloud-analysis's extractor took 78,800 page faults in 64 extractions
/// (13,700 with these settings, 19.3 -> 15.7 ms of CPU each), and on a machine with dear page
/// faults a 50-entity FXAA frame of scene-render took 80 ms instead of 29
/// (docs/performance.md). The resident set stays at its peak, which the benchmarks measure.
/// Call once, first thing in main.
void keep_freed_memory();

}  // namespace stereoscene::support
