#include "tools/eval/job_runner.h"

#include <tbb/global_control.h>
#include <tbb/info.h>
#include "common/job/executor.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>

namespace mlt::eval {

using Clock = std::chrono::steady_clock;

JobRun runJobInProcess(const RenderScene& scene, const RenderSettings& settings, int threads) {
  const int nThreads = threads > 0 ? threads : tbb::info::default_concurrency();
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(nThreads));
  JobRun run;
  const auto start = Clock::now();
  run.plan = planJob(scene, settings);
  run.planSeconds = std::chrono::duration<double>(Clock::now() - start).count();
  const JobPlan& plan = run.plan;
  const size_t nUnits = plan.units.size();
  run.unitStats.reserve(nUnits);
  run.unitSamples.reserve(nUnits);
  // The one executor (common/job/executor.h): the sums do not depend on the thread count.
  UnitExecution e;
  e.parallelism = unitsInFlight(size_t(nThreads));
  e.issue = [&](size_t i) { return i < nUnits; };
  e.run = [&](size_t i) { return runWorkUnit(scene, plan, plan.units[i]); };
  e.merge = [&](size_t, PartialResult& r) {
    run.unitStats.push_back(r.stats);
    run.unitSamples.push_back(r.samples);
    run.merged.add(r);
  };
  executeUnits(e);
  if (nUnits == 0) throw std::runtime_error("runJobInProcess: the plan has no work units");
  run.image = developImage(plan, run.merged);
  run.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return run;
}

uint64_t fnv1a64(const std::string& bytes, uint64_t h) {
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h;
}

std::string sceneContentHash(const SceneDesc& desc) {
  uint64_t h = 0xcbf29ce484222325ULL;
  if (desc.sourceFile.empty()) throw std::invalid_argument("sceneContentHash: the scene has no source file");
  const std::filesystem::path base = std::filesystem::path(desc.sourceFile).parent_path();
  std::vector<std::string> files{desc.sourceFile};
  files.insert(files.end(), desc.referencedFiles.begin(), desc.referencedFiles.end());
  for (const std::string& f : files) {
    h = fnv1a64(std::filesystem::path(f).lexically_relative(base).generic_string() + '\0', h);
    std::ifstream in(f, std::ios::binary);
    if (!in) throw std::runtime_error(f + ": cannot read (for the scene hash)");
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    h = fnv1a64(std::to_string(bytes.size()) + '\0' + bytes, h);
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", (unsigned long long)h);
  return buf;
}

}  // namespace mlt::eval
