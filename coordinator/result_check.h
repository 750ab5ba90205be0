// What an uploaded task result must be before the coordinator counts it: a film the task can hold. Checked
// from the plan alone: the job's film size, the task's units, the sample count its units make, splat
// layers the method can fill, every value finite and on the job's quantization grid (multiples of
// 2^-kQuantumExp, common/mlt/develop.h: what every method's units write), and b's strata layers (whole
// counts, one per large step of their slot). A film that passes may still be
// wrong (only rendering the units again would tell), but one of NaN, infinities, 1e300 counts, the wrong
// size or the wrong sample count never reaches the image.
#pragma once
#include <cstdint>
#include <vector>

#include "common/farm/tasks.h"
#include "common/methods/registry.h"

namespace mlt::farm {

// The highest splat layer a film of `plan` may carry (chain length slots + 1, at most the wire's limit).
uint32_t maxSplatLayer(const JobPlan& plan);

// Throws FarmError(InvalidArgument) naming the field unless `result` fits task `range` of `plan`.
void checkTaskResult(const JobPlan& plan, uint32_t task, TaskRange range, const PartialResult& result);

}  // namespace mlt::farm
