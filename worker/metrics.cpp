// Prometheus metrics of the worker (see metrics.h).
#include "worker/metrics.h"

#include <string>

namespace mlt::farm {
namespace {

prometheus::Family<prometheus::Counter>& counters(prometheus::Registry& r, const std::string& name,
                                                  const std::string& help) {
  return prometheus::BuildCounter().Name(name).Help(help).Register(r);
}

}  // namespace

WorkerMetrics::WorkerMetrics()
    : registry(std::make_shared<prometheus::Registry>()),
      tasksUploaded(counters(*registry, "mltfarm_worker_tasks_total", "Tasks run, by outcome").Add({{"outcome", "uploaded"}})),
      tasksFailed(counters(*registry, "mltfarm_worker_tasks_total", "Tasks run, by outcome").Add({{"outcome", "failed"}})),
      tasksAbandoned(counters(*registry, "mltfarm_worker_tasks_total", "Tasks run, by outcome").Add({{"outcome", "abandoned"}})),
      tasksRunning(prometheus::BuildGauge()
                       .Name("mltfarm_worker_tasks_running")
                       .Help("Tasks in hand (computing or uploading)")
                       .Register(*registry)
                       .Add({})),
      taskSeconds(prometheus::BuildHistogram()
                      .Name("mltfarm_worker_task_duration_seconds")
                      .Help("Seconds computing one task's work units")
                      .Register(*registry)
                      .Add({}, prometheus::Histogram::BucketBoundaries{0.01, 0.03, 0.1, 0.3, 1, 3, 10, 30, 100, 300, 1000})),
      sceneCacheHits(counters(*registry, "mltfarm_worker_cache_hits_total", "Lookups answered from the cache, by cache")
                         .Add({{"cache", "scene"}})),
      sceneCacheMisses(counters(*registry, "mltfarm_worker_cache_misses_total", "Lookups fetched from the coordinator, by cache")
                           .Add({{"cache", "scene"}})),
      planCacheHits(counters(*registry, "mltfarm_worker_cache_hits_total", "Lookups answered from the cache, by cache")
                        .Add({{"cache", "plan"}})),
      planCacheMisses(counters(*registry, "mltfarm_worker_cache_misses_total", "Lookups fetched from the coordinator, by cache")
                          .Add({{"cache", "plan"}})),
      uploadBytes(counters(*registry, "mltfarm_worker_upload_bytes_total", "Film bytes sent to the coordinator").Add({})),
      downloadBytes(counters(*registry, "mltfarm_worker_download_bytes_total",
                             "Scene bundle and plan bytes received from the coordinator")
                        .Add({})) {}

}  // namespace mlt::farm
