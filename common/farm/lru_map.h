// A thread-safe cache of immutable values by key under a byte bound (LruBudget's policy): get() makes a
// missing value once (one thread makes it, the others asking for the same key wait) and returns it pinned:
// while any copy of the returned pointer lives, the entry is in use and never evicted. Entries no task
// uses go least recently used first when the total passes the bound; when everything is in use the cache
// stays over its bound for the while and says so once in the log. What evicting means beyond dropping the
// value (deleting a bundle's files) is the owner's `onEvict`, called under the cache's lock: keep it short.
#pragma once
#include <spdlog/spdlog.h>

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "common/farm/lru_budget.h"

namespace mlt::farm {

template <class V>
class LruMap {
 public:
  using Value = std::shared_ptr<const V>;
  using OnEvict = std::function<void(const std::string& key, const Value& value)>;

  // `name` names the cache in the log; maxBytes > 0 (LruBudget).
  LruMap(std::string name, uint64_t maxBytes, OnEvict onEvict = {})
      : impl_(std::make_shared<Impl>(std::move(name), maxBytes, std::move(onEvict))) {}

  // The value under `key`, made by `make` (returning the value and its size in bytes) if it is not here;
  // pinned while the returned pointer or a copy of it lives. An exception from `make` leaves nothing
  // behind and reaches the caller; the next get() tries again.
  Value get(const std::string& key, const std::function<std::pair<Value, uint64_t>()>& make) {
    for (;;) {
      std::shared_ptr<Slot> slot;
      {
        std::lock_guard lock(impl_->mu);
        auto& s = impl_->slots[key];
        if (!s) s = std::make_shared<Slot>();
        slot = s;
        if (slot->value) return impl_->pinLocked(key, slot->value);
      }
      std::lock_guard build(slot->build);  // one thread makes the value; the others wait for it here
      {
        std::lock_guard lock(impl_->mu);
        auto it = impl_->slots.find(key);
        if (it == impl_->slots.end() || it->second != slot) continue;  // evicted meanwhile: start over
        if (slot->value) return impl_->pinLocked(key, slot->value);
      }
      std::pair<Value, uint64_t> made;
      try {
        made = make();
      } catch (...) {
        std::lock_guard lock(impl_->mu);
        impl_->slots.erase(key);  // ours: a slot without a value is never evicted, and we hold its build lock
        throw;
      }
      std::vector<Value> dropped;  // destroyed after the lock is released
      Value pinned;
      {
        std::lock_guard lock(impl_->mu);
        slot->value = std::move(made.first);
        impl_->budget.put(key, made.second);
        pinned = impl_->pinLocked(key, slot->value);
        dropped = impl_->evictLocked();
      }
      return pinned;
    }
  }

  // Adds a value found rather than made (a bundle left on disk by an earlier worker), unpinned; evicts.
  void adopt(const std::string& key, Value value, uint64_t bytes) {
    std::vector<Value> dropped;
    std::lock_guard lock(impl_->mu);
    auto& s = impl_->slots[key];
    if (s && s->value) return;
    if (!s) s = std::make_shared<Slot>();
    s->value = std::move(value);
    impl_->budget.put(key, bytes);
    dropped = impl_->evictLocked();
  }

  bool contains(const std::string& key) const {
    std::lock_guard lock(impl_->mu);
    return impl_->budget.contains(key);
  }
  uint64_t bytes() const {
    std::lock_guard lock(impl_->mu);
    return impl_->budget.bytes();
  }
  size_t size() const {
    std::lock_guard lock(impl_->mu);
    return impl_->budget.size();
  }

 private:
  struct Slot {
    std::mutex build;
    Value value;  // null until made
  };
  // Shared with the pins handed out: a pointer released after the cache is gone is harmless.
  struct Impl : std::enable_shared_from_this<Impl> {
    Impl(std::string n, uint64_t maxBytes, OnEvict e) : name(std::move(n)), budget(maxBytes), onEvict(std::move(e)) {}
    std::string name;
    mutable std::mutex mu;
    LruBudget budget;
    OnEvict onEvict;
    std::map<std::string, std::shared_ptr<Slot>> slots;

    // A copy of `value` that unpins `key` when its last copy goes.
    Value pinLocked(const std::string& key, const Value& value) {
      budget.touch(key);
      budget.pin(key);
      struct Pin {
        std::shared_ptr<Impl> impl;
        std::string key;
        Value value;
        ~Pin() { impl->release(key); }
      };
      std::shared_ptr<Pin> pin(new Pin{this->shared_from_this(), key, value});  // no temporary Pin to destroy
      return Value(pin, pin->value.get());
    }
    void release(const std::string& key) {
      std::vector<Value> dropped;
      std::lock_guard lock(mu);
      budget.unpin(key);
      dropped = evictLocked();
    }
    // Returns the evicted values, for the caller to destroy after unlocking.
    std::vector<Value> evictLocked() {
      LruBudget::Evicted ev = budget.evict();
      std::vector<Value> dropped;
      for (const std::string& key : ev.keys) {
        auto it = slots.find(key);
        if (it == slots.end()) continue;
        if (onEvict) onEvict(key, it->second->value);
        dropped.push_back(std::move(it->second->value));
        slots.erase(it);
        spdlog::info("event=cache_evicted cache={} key={} bytes_now={} max_bytes={}", name, key.substr(0, 24),
                     budget.bytes(), budget.maxBytes());
      }
      if (ev.newlyOverBound)
        spdlog::warn("event=cache_over_bound cache={} bytes={} max_bytes={} (every entry is in use by a task)", name,
                     budget.bytes(), budget.maxBytes());
      return dropped;
    }
  };
  std::shared_ptr<Impl> impl_;
};

}  // namespace mlt::farm
