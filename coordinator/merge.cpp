// Merging, development and partial EXRs (see merge.h).
#include "coordinator/merge.h"

#include "common/job/executor.h"
#include "common/methods/image_metadata.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <map>
#include <stdexcept>

#include "common/io/png_io.h"
#include "common/methods/chain_report.h"
#include "proto/convert.h"

namespace mlt::farm {
namespace {

std::string toHex(const std::string& bytes) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  out.reserve(bytes.size() * 2);
  for (unsigned char c : bytes) {
    out += digits[c >> 4];
    out += digits[c & 15];
  }
  return out;
}

std::string fromHex(const std::string& hex, const std::string& what) {
  if (hex.size() % 2) throw std::runtime_error(what + ": odd-length hex string");
  auto val = [&](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    throw std::runtime_error(what + ": bad hex digit");
  };
  std::string out(hex.size() / 2, '\0');
  for (size_t i = 0; i < out.size(); ++i) out[i] = char(val(hex[2 * i]) * 16 + val(hex[2 * i + 1]));
  return out;
}

std::string unitList(const std::vector<uint32_t>& units) {
  std::string s;
  for (size_t i = 0; i < units.size();) {
    size_t j = i;
    while (j + 1 < units.size() && units[j + 1] == units[j] + 1) ++j;
    if (!s.empty()) s += ",";
    s += i == j ? fmt::format("{}", units[i]) : fmt::format("{}-{}", units[i], units[j]);
    i = j + 1;
  }
  return s;
}

}  // namespace

ImageMetadata finalMetadata(const JobIdentity& id, const JobPlan& plan, const PartialResult& merged) {
  // The keys of `mltfarm render --in-process` (tools/cli/render_local.cpp), minus wall-clock values that
  // would make the bytes depend on the run, plus the farm's own.
  ImageMetadata m = imageMetadata(plan, merged, id.scene, id.sceneHash);
  m.strings["farm.job"] = id.jobId;
  m.numbers["farm.tasks"] = double(splitTasks(plan).size());
  m.numbers["farm.wireVersion"] = wire::kFormatVersion;
  return m;
}

void writeFinalImages(const std::string& exrPath, const std::string& pngPath, const JobIdentity& id,
                      const JobPlan& plan, const PartialResult& merged) {
  std::vector<Color> rgb = developImage(plan, merged);
  writeExr(exrPath, plan.settings.width, plan.settings.height, rgb, finalMetadata(id, plan, merged));
  if (!pngPath.empty()) writePng(pngPath, plan.settings.width, plan.settings.height, rgb);
}

void writePartialExr(const std::string& path, const JobIdentity& id, const JobPlan& plan, uint32_t task,
                     const PartialResult& result) {
  ImageMetadata m;
  m.strings["farm.job"] = id.jobId;
  m.strings["farm.sceneHash"] = id.sceneHash;
  m.strings["farm.scene"] = id.scene;
  m.strings["farm.method"] = plan.settings.method;
  m.strings["farm.plan"] = toHex(wire::jobPlanBytes(plan));
  m.strings["farm.partial"] = toHex(wire::partialHeaderBytes(result));  // the raw sums are the EXR's channels
  m.strings["farm.unitList"] = unitList(result.units);
  m.numbers["farm.b"] = plan.norm.b;
  for (size_t k = 0; k < plan.norm.bk.size(); ++k) m.numbers[fmt::format("farm.b{}", k)] = plan.norm.bk[k];
  m.numbers["farm.mutations"] = double(result.samples);
  m.numbers["farm.task"] = task;
  m.numbers["farm.tasks"] = double(splitTasks(plan).size());
  m.numbers["farm.wireVersion"] = wire::kFormatVersion;
  writeFilmExr(path, result.film, m, developImage(plan, result));  // the preview: this task's units, exact
}

PartialExr readPartialExr(const std::string& path) {
  // Everything the header claims is checked against the plan it carries before a pixel is allocated.
  PartialExr p;
  std::string headerBytes;
  FilmExr f = readFilmExr(path, [&](const FilmExrHeader& h) {
    auto str = [&](const char* key) {
      auto it = h.metadata.strings.find(key);
      if (it == h.metadata.strings.end())
        throw std::runtime_error(fmt::format("{}: not a farm partial film (no '{}' attribute)", path, key));
      return it->second;
    };
    auto num = [&](const char* key) {
      auto it = h.metadata.numbers.find(key);
      if (it == h.metadata.numbers.end())
        throw std::runtime_error(fmt::format("{}: not a farm partial film (no '{}' attribute)", path, key));
      return it->second;
    };
    auto index = [&](const char* key) {  // a count or index: an integer in [0, 2^32)
      const double v = num(key);
      if (!(v >= 0 && v < 4294967296.0) || v != std::floor(v))
        throw std::runtime_error(fmt::format("{}: {} = {} is not a count", path, key, v));
      return uint32_t(v);
    };
    if (num("farm.wireVersion") != wire::kFormatVersion)
      throw std::runtime_error(fmt::format("{}: farm format version {} (this build reads {})", path,
                                           num("farm.wireVersion"), wire::kFormatVersion));
    p.id = {str("farm.job"), str("farm.sceneHash"), str("farm.scene")};
    try {
      p.planBytes = fromHex(str("farm.plan"), path);
      p.plan = wire::parseJobPlan(p.planBytes);  // validates sizes, depths, unit path lengths
      headerBytes = fromHex(str("farm.partial"), path);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(fmt::format("{}: corrupt farm metadata: {}", path, e.what()));
    }
    p.task = index("farm.task");
    p.tasks = index("farm.tasks");
    const size_t planTasks = splitTasks(p.plan).size();
    if (p.tasks != planTasks || p.task >= p.tasks)
      throw std::runtime_error(fmt::format("{}: task {} of {}, but the plan splits into {} tasks", path, p.task,
                                           p.tasks, planTasks));
    if (h.width != p.plan.settings.width || h.height != p.plan.settings.height)
      throw std::runtime_error(fmt::format("{}: data window {}x{} but the job's film is {}x{}", path, h.width,
                                           h.height, p.plan.settings.width, p.plan.settings.height));
    if (h.splatLayers.back() > wire::kMaxSplatLayer)
      throw std::runtime_error(fmt::format("{}: splat layer {} beyond the largest a job has ({})", path,
                                           h.splatLayers.back(), wire::kMaxSplatLayer));
  });
  if (!f.sumsVerified)
    throw std::runtime_error(fmt::format("{}: no checksum of the raw sums (mltfarm.sumsSha256): not written by the "
                                         "farm, or rewritten by another tool", path));
  try {
    p.result = wire::partialFromHeaderBytes(headerBytes, std::move(f.film));
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(fmt::format("{}: corrupt farm metadata: {}", path, e.what()));
  }
  const TaskRange range = splitTasks(p.plan)[p.task];
  std::vector<uint32_t> expect;
  for (uint32_t u = range.begin; u < range.end; ++u) expect.push_back(u);
  if (p.result.units != expect)
    throw std::runtime_error(fmt::format("{}: task {} holds units {} but the plan says {}", path, p.task,
                                         unitList(p.result.units), unitList(expect)));
  return p;
}

namespace {

// The same file (or both names of one file): `-o` must not overwrite an input.
bool sameFile(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (std::filesystem::equivalent(a, b, ec)) return true;
  return std::filesystem::weakly_canonical(a, ec) == std::filesystem::weakly_canonical(b, ec);
}

}  // namespace

void mergePartialExrs(const std::vector<std::string>& parts, const std::string& exrPath,
                      const std::string& pngPath) {
  if (parts.empty()) throw std::runtime_error("merge: no partial films given");
  for (const std::string& part : parts)
    for (const std::string& out : {exrPath, pngPath})
      if (!out.empty() && sameFile(out, part))
        throw std::runtime_error(fmt::format("merge: the output {} is one of the inputs", out));
  std::vector<PartialExr> loaded;
  for (const std::string& path : parts) loaded.push_back(readPartialExr(path));
  const PartialExr& first = loaded.front();
  std::map<uint32_t, size_t> byTask;
  for (size_t i = 0; i < loaded.size(); ++i) {
    const PartialExr& p = loaded[i];
    auto mismatch = [&](const char* what, const std::string& a, const std::string& b) {
      throw std::runtime_error(fmt::format("merge: {} and {} belong to different renders: {} '{}' vs '{}'",
                                           parts[0], parts[i], what, a, b));
    };
    if (p.id.jobId != first.id.jobId) mismatch("job", first.id.jobId, p.id.jobId);
    if (p.id.sceneHash != first.id.sceneHash) mismatch("scene hash", first.id.sceneHash, p.id.sceneHash);
    if (p.plan.settings.method != first.plan.settings.method)
      mismatch("method", first.plan.settings.method, p.plan.settings.method);
    if (p.plan.settings.width != first.plan.settings.width || p.plan.settings.height != first.plan.settings.height)
      mismatch("size", fmt::format("{}x{}", first.plan.settings.width, first.plan.settings.height),
               fmt::format("{}x{}", p.plan.settings.width, p.plan.settings.height));
    if (p.plan.norm.b != first.plan.norm.b) mismatch("b", fmt::format("{}", first.plan.norm.b), fmt::format("{}", p.plan.norm.b));
    if (p.planBytes != first.planBytes) mismatch("plan", "(first)", "(differs)");
    auto [it, inserted] = byTask.emplace(p.task, i);
    if (!inserted)
      throw std::runtime_error(fmt::format("merge: task {} (units {}) appears twice: {} and {}", p.task,
                                           unitList(p.result.units), parts[it->second], parts[i]));
  }
  const std::vector<TaskRange> tasks = splitTasks(first.plan);  // readPartialExr checked every file's count
  std::vector<std::string> missing;
  for (uint32_t t = 0; t < tasks.size(); ++t)
    if (!byTask.count(t)) missing.push_back(fmt::format("task {} (units {}-{})", t, tasks[t].begin, tasks[t].end - 1));
  if (!missing.empty())
    throw std::runtime_error(fmt::format("merge: {} of {} tasks missing: {}", missing.size(), tasks.size(),
                                         fmt::join(missing, ", ")));
  PartialResult merged = emptyPartial(first.plan);
  for (auto& [t, i] : byTask) merged.add(loaded[i].result);
  // Written next to the outputs and renamed into place: a failure leaves no half-written image.
  const std::string suffix = fmt::format(".tmp-{}", ::getpid());
  const std::string tmpExr = exrPath + suffix, tmpPng = pngPath.empty() ? "" : pngPath + suffix;
  try {
    writeFinalImages(tmpExr, tmpPng, first.id, first.plan, merged);
    std::filesystem::rename(tmpExr, exrPath);
    if (!pngPath.empty()) std::filesystem::rename(tmpPng, pngPath);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmpExr, ec);
    if (!tmpPng.empty()) std::filesystem::remove(tmpPng, ec);
    throw;
  }
}

}  // namespace mlt::farm
