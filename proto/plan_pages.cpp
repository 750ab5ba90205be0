// A job's plan in pages (see plan_pages.h).
#include "proto/plan_pages.h"

#include <fmt/format.h>

#include <algorithm>

namespace mlt::wire {
namespace {

// What every page of one plan repeats: its settings and norm, deterministically encoded.
std::string planIdentity(const v1::JobPlan& page) {
  return deterministicBytes(page.settings()) + deterministicBytes(page.norm());
}

}  // namespace

v1::JobPlan planPage(const JobPlan& plan, uint32_t firstUnit, uint32_t maxUnits) {
  const size_t total = plan.units.size();
  if (firstUnit >= total && !(firstUnit == 0 && total == 0))
    throw PlanPageRangeError("first_unit", fmt::format("{} is beyond the plan's {} units", firstUnit, total));
  const uint32_t n = uint32_t(std::min<size_t>(
      {total - firstUnit, size_t(maxUnits == 0 ? kDefaultPlanPageUnits : std::min(maxUnits, kMaxPlanPageUnits))}));
  JobPlan head;  // settings and norm without the units, which are added from the page's range alone
  head.settings = plan.settings;
  head.norm = plan.norm;
  v1::JobPlan page = toProto(head);
  page.set_total_units(uint32_t(total));
  JobPlan slice;
  slice.units.assign(plan.units.begin() + firstUnit, plan.units.begin() + firstUnit + n);
  *page.mutable_units() = std::move(*toProto(slice).mutable_units());
  return page;
}

JobPlan assemblePlanPages(const std::function<v1::JobPlan(uint32_t firstUnit)>& fetch, uint64_t* bytes) {
  v1::JobPlan whole = fetch(0);
  uint64_t received = whole.ByteSizeLong();
  const uint32_t total = whole.total_units();
  if (total > kMaxPlanUnits)
    throw WireError("plan.total_units", fmt::format("{} units exceeds the limit of {}", total, kMaxPlanUnits));
  if (uint32_t(whole.units_size()) > total)
    throw WireError("plan.units", fmt::format("the first page holds {} units of a plan of {}", whole.units_size(), total));
  const std::string identity = planIdentity(whole);
  whole.mutable_units()->Reserve(int(total));
  while (uint32_t(whole.units_size()) < total) {
    const uint32_t first = uint32_t(whole.units_size());
    v1::JobPlan page = fetch(first);
    received += page.ByteSizeLong();
    if (page.total_units() != total)
      throw WireError("plan.total_units", fmt::format("the page at unit {} belongs to a plan of {} units, not {}",
                                                      first, page.total_units(), total));
    if (planIdentity(page) != identity)
      throw WireError("plan.settings", fmt::format("the page at unit {} has other settings or norm than the first "
                                                   "page: not the same plan", first));
    if (page.units_size() == 0 || uint32_t(page.units_size()) > total - first)
      throw WireError("plan.units", fmt::format("the page at unit {} holds {} units, {} are missing", first,
                                                page.units_size(), total - first));
    if (page.units(0).index() != first)
      throw WireError("plan.units.index", fmt::format("the page asked at unit {} starts at unit {}", first,
                                                      page.units(0).index()));
    for (auto& u : *page.mutable_units()) *whole.add_units() = std::move(u);
  }
  if (bytes) *bytes = received;
  return fromProto(whole);  // validates every unit's index (index i at position i) and range
}

}  // namespace mlt::wire
