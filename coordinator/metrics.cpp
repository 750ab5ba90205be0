// Prometheus metrics of the coordinator (see metrics.h).
#include "coordinator/metrics.h"

#include <prometheus/metric_family.h>

#include <fmt/format.h>
#include <map>

#include "coordinator/coordinator.h"

namespace mlt::farm {
namespace {

using prometheus::ClientMetric;
using prometheus::MetricFamily;
using prometheus::MetricType;

prometheus::Counter& counter(prometheus::Registry& r, const std::string& name, const std::string& help) {
  return prometheus::BuildCounter().Name(name).Help(help).Register(r).Add({});
}

prometheus::Histogram& histogram(prometheus::Registry& r, const std::string& name, const std::string& help,
                                 prometheus::Histogram::BucketBoundaries buckets) {
  return prometheus::BuildHistogram().Name(name).Help(help).Register(r).Add({}, std::move(buckets));
}

// A family of gauges (or counters) filled at scrape time.
struct Family {
  MetricFamily f;
  Family(std::string name, std::string help, MetricType type = MetricType::Gauge) {
    f.name = std::move(name);
    f.help = std::move(help);
    f.type = type;
  }
  void add(double value, std::vector<ClientMetric::Label> labels = {}) {
    ClientMetric m;
    m.label = std::move(labels);
    if (f.type == MetricType::Counter) m.counter.value = value;
    else m.gauge.value = value;
    f.metric.push_back(std::move(m));
  }
};

class FarmCollector final : public prometheus::Collectable {
 public:
  explicit FarmCollector(Coordinator& c) : c_(c) {}

  std::vector<MetricFamily> Collect() const override {
    const FarmSnapshot s = c_.snapshot();
    Family jobs("mltfarm_jobs", "Jobs by state");
    Family tasks("mltfarm_tasks", "Tasks of the jobs not yet finished, by state (queued, leased, accepted)");
    Family workers("mltfarm_workers_connected", "Workers registered and seen within three lease timeouts");
    Family leasedBy("mltfarm_worker_leased_tasks", "Tasks each worker holds");
    Family progress("mltfarm_job_progress_ratio", "Work done over work planned, per job not yet finished");
    Family eta("mltfarm_job_eta_seconds", "Estimated seconds to the end of rendering (running jobs with an estimate)");
    Family b("mltfarm_job_b", "Normalization constant b estimated by the bootstrap, per job");
    Family bRse("mltfarm_job_b_relative_stderr", "Relative standard error of b (stderr / b), per job");
    Family bootstrap("mltfarm_job_bootstrap_seconds", "Seconds the job's bootstrap took");
    Family samples("mltfarm_job_samples_total", "Pixel samples (sample methods) or mutations (chains) of the accepted tasks",
                   MetricType::Counter);
    Family rate("mltfarm_job_samples_per_second", "Accepted pixel samples or mutations per second of rendering, running jobs");
    Family acc("mltfarm_job_chain_acceptance_ratio",
               "Metropolis acceptance of the accepted tasks' chains per path length (pssmlt: path_length 0)");
    std::map<JobState, int> byState;
    for (int st = int(JobState::Queued); st <= int(JobState::Cancelled); ++st) byState[JobState(st)] = 0;
    uint64_t queued = 0, leased = 0, accepted = 0;
    for (const JobSnapshot& j : s.jobs) {
      ++byState[j.status.state];
      if (isTerminal(j.status.state)) continue;  // per-job series only while a job is live
      queued += j.queuedTasks;
      leased += j.status.leasedTasks;
      accepted += j.status.tasksDone;
      const std::vector<ClientMetric::Label> job{{"job", j.status.jobId}, {"method", j.status.method}};
      if (j.status.workTotal > 0) progress.add(double(j.status.workDone) / double(j.status.workTotal), job);
      if (j.status.etaSeconds >= 0) eta.add(j.status.etaSeconds, job);
      if (j.status.state < JobState::Running) continue;  // no plan yet
      b.add(j.status.b, job);
      if (j.status.b > 0) bRse.add(j.status.bStdErr / j.status.b, job);
      bootstrap.add(j.status.bootstrapSeconds, job);
      samples.add(double(j.samplesAccepted), job);
      if (j.status.state == JobState::Running) rate.add(j.samplesPerSecond, job);
      for (size_t k = 0; k < j.proposedPerLength.size(); ++k) {
        if (j.proposedPerLength[k] == 0) continue;
        auto labels = job;
        labels.push_back({"path_length", std::to_string(k)});
        const uint64_t a = k < j.acceptedPerLength.size() ? j.acceptedPerLength[k] : 0;
        acc.add(double(a) / double(j.proposedPerLength[k]), labels);
      }
    }
    for (auto [st, n] : byState) jobs.add(n, {{"state", jobStateName(st)}});
    tasks.add(double(queued), {{"state", "queued"}});
    tasks.add(double(leased), {{"state", "leased"}});
    tasks.add(double(accepted), {{"state", "accepted"}});
    workers.add(double(s.workers.size()));
    for (const WorkerSnapshot& w : s.workers)
      leasedBy.add(double(w.tasks.size()), {{"worker", w.workerId}, {"host", w.hostname}});
    std::vector<MetricFamily> out;
    for (Family* f : {&jobs, &tasks, &workers, &leasedBy, &progress, &eta, &b, &bRse, &bootstrap, &samples, &rate, &acc})
      out.push_back(std::move(f->f));
    return out;
  }

 private:
  Coordinator& c_;
};

}  // namespace

CoordinatorMetrics::CoordinatorMetrics()
    : registry(std::make_shared<prometheus::Registry>()),
      jobsSubmitted(counter(*registry, "mltfarm_jobs_submitted_total", "Jobs accepted by SubmitJob")),
      tasksLeased(counter(*registry, "mltfarm_tasks_leased_total", "Tasks leased to workers")),
      tasksAccepted(counter(*registry, "mltfarm_tasks_accepted_total", "Task results accepted (persisted, counted once)")),
      tasksRequeued(counter(*registry, "mltfarm_tasks_requeued_total",
                            "Tasks queued again: after a failed attempt or an expired lease, or returned by a stopping worker")),
      taskFailures(counter(*registry, "mltfarm_task_failures_total",
                           "Failed task attempts: worker error reports and expired leases")),
      leasesExpired(counter(*registry, "mltfarm_leases_expired_total", "Leases not renewed within the lease timeout")),
      uploadsRefused(counter(*registry, "mltfarm_uploads_refused_total",
                             "Uploads not counted: the task was already accepted or the job is no longer running")),
      uploadBytes(counter(*registry, "mltfarm_upload_bytes_total", "Film bytes received by UploadResult")),
      uploadSeconds(histogram(*registry, "mltfarm_upload_duration_seconds",
                              "UploadResult from its first message to the reply (receive, check, persist)",
                              {0.001, 0.003, 0.01, 0.03, 0.1, 0.3, 1, 3, 10, 30})),
      bootstrapSeconds(histogram(*registry, "mltfarm_bootstrap_duration_seconds", "Bootstrap phase of a job",
                                 {0.01, 0.03, 0.1, 0.3, 1, 3, 10, 30, 100, 300})) {}

std::shared_ptr<prometheus::Collectable> farmCollector(Coordinator& coordinator) {
  return std::make_shared<FarmCollector>(coordinator);
}

}  // namespace mlt::farm
