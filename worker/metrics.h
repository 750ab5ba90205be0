// Prometheus metrics of the worker (mltfarm-worker --metrics-listen ADDR; off by default), counted where
// the events happen: tasks run by outcome and their duration, the scene and plan caches, bytes moved to
// and from the coordinator. Names follow Prometheus conventions (mltfarm_worker_*, _total, _seconds, _bytes).
#pragma once
#include <prometheus/counter.h>
#include <prometheus/gauge.h>
#include <prometheus/histogram.h>
#include <prometheus/registry.h>

#include <memory>

namespace mlt::farm {

class WorkerMetrics {
 public:
  WorkerMetrics();
  std::shared_ptr<prometheus::Registry> registry;
  prometheus::Counter& tasksUploaded;    // the film reached the coordinator (accepted or not)
  prometheus::Counter& tasksFailed;      // an error (reported to the coordinator when it can be reached)
  prometheus::Counter& tasksAbandoned;   // cancelled by the coordinator or returned on shutdown
  prometheus::Gauge& tasksRunning;
  prometheus::Histogram& taskSeconds;    // computing one task's units (the film, before the upload)
  prometheus::Counter& sceneCacheHits;   // the bundle was on disk (or being fetched by another task)
  prometheus::Counter& sceneCacheMisses; // fetched from the coordinator
  prometheus::Counter& planCacheHits;
  prometheus::Counter& planCacheMisses;
  prometheus::Counter& uploadBytes;      // film bytes sent (UploadResult)
  prometheus::Counter& downloadBytes;    // scene bundles and plans received
};

}  // namespace mlt::farm
