// Worker and lease ids that the coordinator can recognize as its own: each carries a MAC (HMAC-SHA-256,
// truncated to 128 bits) under a key kept in the state directory (STATE/lease.key, created on first
// start). A made-up id fails the check; an id issued before a restart of the same state directory passes
// it, so a worker keeps its id and its leases across a coordinator restart (the coordinator takes a lease
// back if nobody else holds its task, see worker_handler.cpp) and a film finished while the coordinator
// was away is still accepted from the worker that was leased its task.
//   worker id: w<instance>-<n>.<mac>                 mac over "worker|w<instance>-<n>"
//   lease id:  l<instance>-<n>.<job>.<task>.<mac>    mac over "lease|l<instance>-<n>.<job>.<task>|<worker id>"
#pragma once
#include <cstdint>
#include <optional>
#include <string>

namespace mlt::farm {

struct LeaseClaim {
  int64_t job = 0;
  uint32_t task = 0;
};

class Credentials {
 public:
  // Reads STATE/lease.key, or creates it (32 random bytes, mode 0600). Throws FarmError naming the file.
  explicit Credentials(const std::string& stateDir);

  std::string workerId(const std::string& instance, uint64_t n) const;
  bool validWorker(const std::string& workerId) const;
  std::string leaseId(const std::string& instance, uint64_t n, int64_t job, uint32_t task,
                      const std::string& workerId) const;
  // The job and task a lease id names, if it is a lease this state directory issued to `workerId`.
  std::optional<LeaseClaim> parseLease(const std::string& leaseId, const std::string& workerId) const;

 private:
  std::string mac(const std::string& message) const;  // 32 hex digits
  std::string key_;
};

}  // namespace mlt::farm
