// Memory policy of the farm's long-running processes (mltfarm-worker, mltfarm-coordinator).
#pragma once

namespace mlt::farm {

// A task's merged film, its wire chunks and the coordinator's decoded copy are a few MiB each and come
// and go once per task. glibc serves blocks that large with mmap and returns them with munmap (or trims
// them off the heap), so every task touched fresh zero pages again: ~35 k page faults per default job
// beyond the in-process renderer's (tests/bench/farm_overhead.sh, perf stat). This keeps blocks up to
// 32 MiB on the heap and freed memory in the process (trimmed only above 512 MiB free), so the next task
// reuses it. Call once, first thing in main().
void keepFreedMemoryForReuse();

}  // namespace mlt::farm
