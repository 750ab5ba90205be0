#include "common/farm/process_memory.h"

#include <malloc.h>

namespace mlt::farm {

void keepFreedMemoryForReuse() {
  // M_MMAP_THRESHOLD at most HEAP_MAX_SIZE / 2 (32 MiB on 64-bit glibc); larger blocks are mmapped anyway.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
}

}  // namespace mlt::farm
