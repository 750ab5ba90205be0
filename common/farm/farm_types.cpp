// Names of the farm's domain values (see farm_types.h).
#include "common/farm/farm_types.h"

namespace mlt::farm {

const char* jobStateName(JobState s) {
  switch (s) {
    case JobState::Queued: return "QUEUED";
    case JobState::Planning: return "PLANNING";
    case JobState::Running: return "RUNNING";
    case JobState::Merging: return "MERGING";
    case JobState::Done: return "DONE";
    case JobState::Failed: return "FAILED";
    case JobState::Cancelled: return "CANCELLED";
  }
  return "?";
}

}  // namespace mlt::farm
