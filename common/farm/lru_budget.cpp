// LRU accounting under a byte bound (see lru_budget.h).
#include "common/farm/lru_budget.h"

#include <fmt/format.h>

#include <stdexcept>

namespace mlt::farm {

LruBudget::LruBudget(uint64_t maxBytes) : max_(maxBytes) {
  if (maxBytes == 0) throw std::invalid_argument("cache bound: the maximum size must be greater than 0 bytes");
}

LruBudget::Entry& LruBudget::at(const std::string& key) {
  auto it = entries_.find(key);
  if (it == entries_.end()) throw std::logic_error(fmt::format("cache: no entry '{}'", key));
  return it->second;
}

void LruBudget::put(const std::string& key, uint64_t bytes) {
  auto [it, added] = entries_.try_emplace(key);
  Entry& e = it->second;
  if (added) {
    e.pos = lru_.insert(lru_.end(), key);
  } else {
    bytes_ -= e.bytes;
    lru_.splice(lru_.end(), lru_, e.pos);
  }
  e.bytes = bytes;
  bytes_ += bytes;
}

bool LruBudget::touch(const std::string& key) {
  auto it = entries_.find(key);
  if (it == entries_.end()) return false;
  lru_.splice(lru_.end(), lru_, it->second.pos);
  return true;
}

void LruBudget::pin(const std::string& key) { ++at(key).pins; }

void LruBudget::unpin(const std::string& key) {
  Entry& e = at(key);
  if (e.pins <= 0) throw std::logic_error(fmt::format("cache: '{}' unpinned more often than pinned", key));
  --e.pins;
}

bool LruBudget::pinned(const std::string& key) const {
  auto it = entries_.find(key);
  return it != entries_.end() && it->second.pins > 0;
}

void LruBudget::erase(const std::string& key) {
  auto it = entries_.find(key);
  if (it == entries_.end()) return;
  bytes_ -= it->second.bytes;
  lru_.erase(it->second.pos);
  entries_.erase(it);
}

LruBudget::Evicted LruBudget::evict() {
  Evicted out;
  for (auto pos = lru_.begin(); bytes_ > max_ && pos != lru_.end();) {
    Entry& e = entries_.at(*pos);
    if (e.pins > 0) {
      ++pos;
      continue;
    }
    out.keys.push_back(*pos);
    bytes_ -= e.bytes;
    entries_.erase(*pos);
    pos = lru_.erase(pos);
  }
  out.overBound = bytes_ > max_;
  out.newlyOverBound = out.overBound && !over_;
  over_ = out.overBound;
  return out;
}

}  // namespace mlt::farm
