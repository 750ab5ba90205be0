// Merging partial results (element-wise sums, checked).
#include "common/job/job_types.h"

#include <algorithm>
#include <stdexcept>
#include <string>


namespace mlt {

namespace {
template <class T>
void addVectors(std::vector<T>& a, const std::vector<T>& b) {
  if (a.size() < b.size()) a.resize(b.size(), T(0));
  for (size_t i = 0; i < b.size(); ++i) a[i] += b[i];
}
}  // namespace

void ChainStats::add(const ChainStats& o) {
  addVectors(proposedPerLength, o.proposedPerLength);
  addVectors(acceptedPerLength, o.acceptedPerLength);
  addVectors(proposedPerKind, o.proposedPerKind);
  addVectors(acceptedPerKind, o.acceptedPerKind);
  addVectors(proposedPerLengthKind, o.proposedPerLengthKind);
  addVectors(acceptedPerLengthKind, o.acceptedPerLengthKind);
  addVectors(secondsPerKind, o.secondsPerKind);
  addPerSlot(largeStepSums, o.largeStepSums);
  addPerSlot(largeStepLuminanceSums, o.largeStepLuminanceSums);
}

void PartialResult::add(const PartialResult& o) {
  // Check everything before changing anything, so a rejected result leaves this one intact.
  std::vector<uint32_t> theirs = o.units;
  std::sort(theirs.begin(), theirs.end());
  if (std::adjacent_find(theirs.begin(), theirs.end()) != theirs.end())
    throw std::invalid_argument("PartialResult::add: work unit " +
                                std::to_string(*std::adjacent_find(theirs.begin(), theirs.end())) +
                                " appears twice in the added result");
  // Units added in index order (the executor, a task's units, the coordinator's tasks) all follow ours:
  // no overlap and a plain append, so that summing n units costs O(n), not O(n^2) (issue 13's plans of
  // up to 2^20 units).
  const bool after = units.empty() || theirs.empty() || theirs.front() > units.back();
  std::vector<uint32_t> common;
  if (!after)
    std::set_intersection(units.begin(), units.end(), theirs.begin(), theirs.end(), std::back_inserter(common));
  if (!common.empty())
    throw std::invalid_argument("PartialResult::add: work unit " + std::to_string(common.front()) +
                                " is already included");
  foldSplats();  // ours (a unit's result being added to): the same sums, now in `film`
  const bool emptyFilm = film.width() == 0 && film.height() == 0;
  auto sameSize = [&](int w, int h) { return emptyFilm || (film.width() == w && film.height() == h); };
  if ((o.film.pixelCount() > 0 && !sameSize(o.film.width(), o.film.height())) ||
      (!o.splats.empty() && !sameSize(o.splats.width, o.splats.height)) ||
      (o.film.pixelCount() > 0 && !o.splats.empty() &&
       (o.film.width() != o.splats.width || o.film.height() != o.splats.height)))
    throw std::invalid_argument("PartialResult::add: film size mismatch");

  if (emptyFilm && o.film.pixelCount() > 0) film = o.film;
  else if (o.film.pixelCount() > 0) film.merge(o.film);
  o.splats.addTo(film);  // an empty film first becomes one of the splats' size
  samples += o.samples;
  stats.add(o.stats);
  if (after) {
    units.insert(units.end(), theirs.begin(), theirs.end());
  } else {
    std::vector<uint32_t> merged;
    merged.reserve(units.size() + theirs.size());
    std::merge(units.begin(), units.end(), theirs.begin(), theirs.end(), std::back_inserter(merged));
    units = std::move(merged);
  }
  seconds += o.seconds;
}

void PartialResult::foldSplats() {
  splats.addTo(film);
  splats = SparseSplats{};
}

}  // namespace mlt
