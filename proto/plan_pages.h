// A job's plan in pages (issue 13): FetchPlan answers the units [first_unit, first_unit + n) of a plan
// with its settings, norm and total unit count, so that a plan of up to 2^20 units (kMaxChains, kMaxSpp)
// never needs a reply over gRPC's 4 MiB receive limit. The server side cuts a page from the plan; the
// client side fetches pages until it holds every unit, checks that each page belongs to the same plan
// (total, settings and norm byte for byte, unit indices) and assembles the whole plan.
#pragma once
#include <cstdint>
#include <functional>

#include "proto/convert.h"

namespace mlt::wire {

// A WorkUnit encodes to at most 62 bytes (7 varint/fixed fields + its tag and length), so a page of
// kMaxPlanPageUnits units is at most ~1 MiB, next to settings and norm of tens of KiB at most.
inline constexpr uint32_t kMaxPlanPageUnits = 16384;
inline constexpr uint32_t kDefaultPlanPageUnits = kMaxPlanPageUnits;  // a request's max_units 0
// More units than any valid plan holds (2^20 chains plus a separate direct pass's batches): a page that
// announces more is refused before anything is reserved.
inline constexpr uint32_t kMaxPlanUnits = 1u << 22;

// first_unit outside the plan (the service answers OUT_OF_RANGE).
class PlanPageRangeError : public WireError {
 public:
  using WireError::WireError;
};

// The page of `plan` starting at `firstUnit` with at most `maxUnits` units (0: the default page), capped
// at kMaxPlanPageUnits. Throws PlanPageRangeError unless firstUnit < the unit count (or both are 0).
v1::JobPlan planPage(const JobPlan& plan, uint32_t firstUnit, uint32_t maxUnits);

// The whole plan from pages: `fetch(firstUnit)` returns the page that starts there. Throws WireError
// naming the field when a page is empty, does not start at firstUnit, or is not of the same plan as the
// first (total_units, settings, norm). `bytes`, if given, receives the pages' size on the wire.
JobPlan assemblePlanPages(const std::function<v1::JobPlan(uint32_t firstUnit)>& fetch, uint64_t* bytes = nullptr);

}  // namespace mlt::wire
