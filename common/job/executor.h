// The one executor of work units. The in-process renderer (tools/cli/render_local.cpp), the evaluation
// harness (tools/eval/job_runner.cpp) and a farm task on a worker (coordinator/merge.cpp runTask) all run
// units through it:
//   units are issued in index order 0, 1, 2, ... while issue(i) says so (a time budget or a cancel stops
//   issuing; a unit in flight always finishes), run with up to `parallelism` in flight, and handed to
//   merge(i, result) strictly in index order,
// so the merged sums, and the image's bits, never depend on the thread count or on timing.
// runUnits (common/methods/registry.h) runs a range of a plan's units through it.
#pragma once
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>

#include "common/job/job_types.h"

namespace mlt {

struct UnitExecution {
  size_t parallelism = 1;                           // units in flight; 1: one after another, this thread
  std::function<bool(size_t)> issue;                // start unit i? (false: stop issuing)
  std::function<PartialResult(size_t)> run;         // the unit's result
  std::function<void(size_t, PartialResult&)> merge;  // called in index order
};

// Units in flight for `threads` threads. Merging strictly in index order holds a finished unit's token
// until every unit before it is merged: with one token per thread, a long unit (a long chain, a deep
// path length) leaves the other threads idle behind it. Two per thread keep them busy.
inline size_t unitsInFlight(size_t threads) { return 2 * (threads > 0 ? threads : 1); }

// Returns the number of units merged (= issued).
size_t executeUnits(const UnitExecution& e);

// A zero partial result with the plan's film size (what units are summed into).
PartialResult emptyPartial(const JobPlan& plan);

}  // namespace mlt
