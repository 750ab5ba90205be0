#include "common/job/executor.h"

#include <tbb/parallel_pipeline.h>

#include <memory>
#include <stdexcept>
#include <utility>

namespace mlt {

size_t executeUnits(const UnitExecution& e) {
  if (!e.issue || !e.run || !e.merge) throw std::invalid_argument("executeUnits: issue, run and merge are required");
  size_t issued = 0, merged = 0;
  if (e.parallelism <= 1) {
    for (size_t i = 0; e.issue(i); ++i) {
      PartialResult r = e.run(i);
      e.merge(i, r);
      ++merged;
    }
    return merged;
  }
  using Item = std::pair<size_t, std::shared_ptr<PartialResult>>;
  tbb::parallel_pipeline(
      e.parallelism,
      tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order,
                                     [&](tbb::flow_control& fc) -> size_t {
                                       if (!e.issue(issued)) {
                                         fc.stop();
                                         return 0;
                                       }
                                       return issued++;
                                     }) &
          tbb::make_filter<size_t, Item>(tbb::filter_mode::parallel,
                                         [&](size_t i) { return Item(i, std::make_shared<PartialResult>(e.run(i))); }) &
          tbb::make_filter<Item, void>(tbb::filter_mode::serial_in_order, [&](const Item& r) {
            e.merge(r.first, *r.second);
            ++merged;
          }));
  return merged;
}

PartialResult emptyPartial(const JobPlan& plan) {
  PartialResult r;
  r.film = Film(plan.settings.width, plan.settings.height);
  return r;
}

bool runUnits(const RenderScene& scene, const JobPlan& plan, uint32_t begin, uint32_t end, PartialResult& out,
              const std::atomic<bool>* cancel, size_t parallelism) {
  if (begin > end || end > plan.units.size())
    throw std::invalid_argument("runUnits: units [" + std::to_string(begin) + ", " + std::to_string(end) +
                                ") outside the plan's " + std::to_string(plan.units.size()));
  out = emptyPartial(plan);
  UnitExecution e;
  e.issue = [&](size_t i) { return begin + i < end && !(cancel && cancel->load()); };
  e.run = [&](size_t i) { return runWorkUnit(scene, plan, plan.units[begin + i]); };
  e.merge = [&](size_t, PartialResult& r) { out.add(r); };
  e.parallelism = parallelism;
  return executeUnits(e) == size_t(end - begin);
}

}  // namespace mlt
