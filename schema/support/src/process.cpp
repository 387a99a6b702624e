#include "stereoscene/support/process.hpp"

#include <malloc.h>

namespace stereoscene::support {

void keep_freed_memory() {
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 128 << 20);
}

}  // namespace stereoscene::support
