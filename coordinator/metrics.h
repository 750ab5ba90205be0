// Prometheus metrics of the coordinator (mltfarm-coordinator --metrics-listen ADDR; off by default).
// Two kinds, exposed together on GET /metrics:
//  - events, counted where they happen (CoordinatorMetrics: a prometheus::Registry of counters and
//    histograms the coordinator's roles increment; thread-safe, cheap enough to keep on always);
//  - state, read at scrape time from Coordinator::snapshot() (farmCollector): jobs by state, tasks queued
//    and leased, workers connected, and per job of the jobs not yet finished: progress, b and its
//    relative standard error, samples (pixel samples or mutations) per second, chain acceptance per path
//    length.
// Names follow Prometheus conventions: prefix mltfarm_, counters end in _total, units _seconds / _bytes.
#pragma once
#include <prometheus/collectable.h>
#include <prometheus/counter.h>
#include <prometheus/histogram.h>
#include <prometheus/registry.h>

#include <memory>
#include <string>
#include <vector>

namespace mlt::farm {

class Coordinator;

class CoordinatorMetrics {
 public:
  CoordinatorMetrics();
  std::shared_ptr<prometheus::Registry> registry;
  prometheus::Counter& jobsSubmitted;
  prometheus::Counter& tasksLeased;
  prometheus::Counter& tasksAccepted;
  prometheus::Counter& tasksRequeued;   // after a failure or an expired lease, or returned by a stopping worker
  prometheus::Counter& taskFailures;    // failed attempts: worker error reports and expired leases
  prometheus::Counter& leasesExpired;
  prometheus::Counter& uploadsRefused;  // duplicates, or the job no longer running
  prometheus::Counter& uploadBytes;     // film bytes received on the wire (UploadResult)
  prometheus::Histogram& uploadSeconds; // UploadResult: first message read to reply (receive, check, persist)
  prometheus::Histogram& bootstrapSeconds;
};

// The scrape-time state of `coordinator` (see above); keeps a reference: outlive it with the coordinator.
std::shared_ptr<prometheus::Collectable> farmCollector(Coordinator& coordinator);

}  // namespace mlt::farm
