#include "tools/eval/reference.h"

#include <cstdio>
#include <filesystem>

#include <fmt/format.h>

#include "common/io/exr_io.h"
#include "common/core/rng.h"
#include "tools/eval/job_runner.h"

namespace mlt::eval {

namespace fs = std::filesystem;

std::string referenceCacheKey(const std::string& sceneHash, const RenderSettings& base,
                              const ReferenceSettings& s) {
  std::string text = fmt::format("{}|{}|spp={}|parts={}|seed={}|{}x{}|depth={}|rr={}", sceneHash,
                                 s.method, s.spp, s.parts, s.seed, base.width, base.height,
                                 base.integrator.maxDepth, base.integrator.rrDepth);
  return fmt::format("{:016x}", fnv1a64(text));
}

static std::string describe(const ReferenceSettings& s, const std::string& key) {
  return fmt::format("{} spp={} parts={} (cache key {})", s.method, s.spp, s.parts, key);
}

Reference loadUserReference(const std::string& path, const std::string& sceneName, int width, int height) {
  ExrImage exr = readExr(path);
  if (exr.width != width || exr.height != height)
    throw std::runtime_error(fmt::format("{}: reference is {}x{}, the runs render {}x{} (scene {})", path, exr.width,
                                         exr.height, width, height, sceneName));
  Reference ref;
  ref.width = width;
  ref.height = height;
  ref.image = std::move(exr.rgb);
  ref.info.scene = sceneName;
  ref.info.source = "user:" + path;
  ref.info.noise.parts = 0;  // unknown
  return ref;
}

Reference obtainReference(const RenderScene& scene, const RenderSettings& base, const ReferenceSettings& settings,
                          const std::string& sceneName, const std::string& sceneHash, const std::string& cacheDir,
                          double eps, int threads) {
  if (settings.parts < 2) throw std::invalid_argument("reference: --ref-parts must be >= 2 (to estimate its noise)");
  if (settings.spp < settings.parts)
    throw std::invalid_argument("reference: --ref-spp must be at least the number of parts");
  const bool useCache = !cacheDir.empty() && !sceneHash.empty();
  const std::string key = useCache ? referenceCacheKey(sceneHash, base, settings) : std::string("none");
  const fs::path exrPath = fs::path(cacheDir) / (key + ".exr");
  const fs::path varPath = fs::path(cacheDir) / (key + ".var.exr");
  Reference ref;
  ref.info.scene = sceneName;
  ref.info.source = describe(settings, key);
  if (useCache && fs::exists(exrPath) && fs::exists(varPath)) {
    ExrImage img = readExr(exrPath.string()), var = readExr(varPath.string());
    if (img.width != var.width || img.height != var.height)
      throw std::runtime_error(exrPath.string() + ": cached reference and variance sizes differ; delete the cache");
    auto num = [&](const char* name) {
      auto it = img.metadata.numbers.find(name);
      if (it == img.metadata.numbers.end())
        throw std::runtime_error(exrPath.string() + ": cached reference lacks attribute " + name);
      return it->second;
    };
    ref.width = img.width;
    ref.height = img.height;
    ref.image = std::move(img.rgb);
    ref.variance = std::move(var.rgb);
    ref.info.noise = noiseFromVariance(ref.image, ref.variance, int(num("eval.parts")), num("eval.meanRelStdErr"), eps);
    ref.info.seconds = num("eval.seconds");
    ref.info.cached = true;
    return ref;
  }
  std::vector<std::vector<Color>> parts;
  double seconds = 0;
  RenderSettings rs = base;
  rs.method = settings.method;
  rs.spp = settings.spp / settings.parts;
  rs.samplesPerUnit = 0;
  for (int k = 0; k < settings.parts; ++k) {
    rs.seed = hashKeys(settings.seed, uint64_t(k));
    JobRun run = runJobInProcess(scene, rs, threads);
    seconds += run.seconds;
    ref.width = run.plan.settings.width;
    ref.height = run.plan.settings.height;
    parts.push_back(std::move(run.image));
  }
  ReferenceEstimate est = estimateReference(parts, eps);
  ref.image = std::move(est.mean);
  ref.variance = std::move(est.variance);
  ref.info.noise = est.noise;
  ref.info.seconds = seconds;
  if (useCache) {
    fs::create_directories(cacheDir);
    ImageMetadata m;
    m.strings["eval.scene"] = sceneName;
    m.strings["eval.sceneHash"] = sceneHash;
    m.strings["eval.source"] = ref.info.source;
    m.numbers["eval.parts"] = settings.parts;
    m.numbers["eval.spp"] = settings.spp;
    m.numbers["eval.meanRelStdErr"] = est.noise.meanRelStdErr;
    m.numbers["eval.relMSEFloor"] = est.noise.relMSEFloor;
    m.numbers["eval.seconds"] = seconds;
    // Write to temporary names first so an interrupted run never leaves a half-written cache entry.
    const fs::path tmpExr = exrPath.string() + ".tmp.exr", tmpVar = varPath.string() + ".tmp.exr";
    writeExr(tmpExr.string(), ref.width, ref.height, ref.image, m);
    writeExr(tmpVar.string(), ref.width, ref.height, ref.variance, m);
    fs::rename(tmpVar, varPath);
    fs::rename(tmpExr, exrPath);
  }
  return ref;
}

}  // namespace mlt::eval
