// The eviction policy of the worker's caches (scene bundles, built scenes, job plans): entries by key with
// a size in bytes; when the total passes the bound, the least recently used entries go first. An entry is
// pinned while a task uses it and is never evicted then: if the pinned entries alone pass the bound, the
// total stays over it until they are released. No values and no locking here: the cache that owns the
// values (common/farm/lru_map.h) holds its own mutex around every call and decides what evicting means.
#pragma once
#include <cstdint>
#include <list>
#include <string>
#include <unordered_map>
#include <vector>

namespace mlt::farm {

class LruBudget {
 public:
  // maxBytes > 0; std::invalid_argument otherwise (there is no "unbounded").
  explicit LruBudget(uint64_t maxBytes);

  // Adds `key` with `bytes` (or resizes it) and marks it the most recently used.
  void put(const std::string& key, uint64_t bytes);
  // Marks `key` the most recently used; false if it is not here.
  bool touch(const std::string& key);
  // A pinned key is never evicted; pins count (each pin() needs its unpin()). The key must be here.
  void pin(const std::string& key);
  void unpin(const std::string& key);
  void erase(const std::string& key);
  bool contains(const std::string& key) const { return entries_.count(key) > 0; }
  bool pinned(const std::string& key) const;

  struct Evicted {
    std::vector<std::string> keys;  // least recently used first; already out of the accounting
    bool overBound = false;         // still over the bound after evicting: everything left is pinned
    bool newlyOverBound = false;    // ... and it was not after the previous evict() (log it once)
  };
  // Takes least recently used unpinned entries out until the total fits the bound.
  Evicted evict();

  uint64_t bytes() const { return bytes_; }
  uint64_t maxBytes() const { return max_; }
  size_t size() const { return entries_.size(); }
  std::vector<std::string> order() const { return {lru_.begin(), lru_.end()}; }  // least recently used first

 private:
  struct Entry {
    uint64_t bytes = 0;
    int pins = 0;
    std::list<std::string>::iterator pos;
  };
  Entry& at(const std::string& key);
  uint64_t max_;
  uint64_t bytes_ = 0;
  bool over_ = false;
  std::list<std::string> lru_;  // front: least recently used
  std::unordered_map<std::string, Entry> entries_;
};

}  // namespace mlt::farm
