// Merging, development and partial EXRs (see merge.h).
#include "coordinator/merge.h"

#include "common/job/executor.h"
#include "common/methods/image_metadata.h"

#include <algorithm>
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
  FilmExr f = readFilmExr(path);
  auto str = [&](const char* key) {
    auto it = f.metadata.strings.find(key);
    if (it == f.metadata.strings.end())
      throw std::runtime_error(fmt::format("{}: not a farm partial film (no '{}' attribute)", path, key));
    return it->second;
  };
  auto num = [&](const char* key) {
    auto it = f.metadata.numbers.find(key);
    if (it == f.metadata.numbers.end())
      throw std::runtime_error(fmt::format("{}: not a farm partial film (no '{}' attribute)", path, key));
    return it->second;
  };
  if (num("farm.wireVersion") != wire::kFormatVersion)
    throw std::runtime_error(fmt::format("{}: farm format version {} (this build reads {})", path,
                                         num("farm.wireVersion"), wire::kFormatVersion));
  PartialExr p;
  p.id = {str("farm.job"), str("farm.sceneHash"), str("farm.scene")};
  try {
    p.planBytes = fromHex(str("farm.plan"), path);
    p.plan = wire::parseJobPlan(p.planBytes);
    p.result = wire::partialFromHeaderBytes(fromHex(str("farm.partial"), path), std::move(f.film));
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(fmt::format("{}: corrupt farm metadata: {}", path, e.what()));
  }
  p.task = uint32_t(num("farm.task"));
  p.tasks = uint32_t(num("farm.tasks"));
  if (p.result.film.width() != p.plan.settings.width || p.result.film.height() != p.plan.settings.height)
    throw std::runtime_error(fmt::format("{}: film {}x{} but the plan says {}x{}", path, p.result.film.width(),
                                         p.result.film.height(), p.plan.settings.width, p.plan.settings.height));
  return p;
}

void mergePartialExrs(const std::vector<std::string>& parts, const std::string& exrPath,
                      const std::string& pngPath) {
  if (parts.empty()) throw std::runtime_error("merge: no partial films given");
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
    if (p.tasks != first.tasks || p.task >= p.tasks)
      throw std::runtime_error(fmt::format("merge: {}: task {} of {} is inconsistent", parts[i], p.task, p.tasks));
    auto [it, inserted] = byTask.emplace(p.task, i);
    if (!inserted)
      throw std::runtime_error(fmt::format("merge: task {} (units {}) appears twice: {} and {}", p.task,
                                           unitList(p.result.units), parts[it->second], parts[i]));
  }
  const std::vector<TaskRange> tasks = splitTasks(first.plan);
  if (tasks.size() != first.tasks)
    throw std::runtime_error(fmt::format("merge: the plan splits into {} tasks but the files say {}", tasks.size(),
                                         first.tasks));
  std::vector<std::string> missing;
  for (uint32_t t = 0; t < tasks.size(); ++t)
    if (!byTask.count(t)) missing.push_back(fmt::format("task {} (units {}-{})", t, tasks[t].begin, tasks[t].end - 1));
  if (!missing.empty())
    throw std::runtime_error(fmt::format("merge: {} of {} tasks missing: {}", missing.size(), tasks.size(),
                                         fmt::join(missing, ", ")));
  PartialResult merged = emptyPartial(first.plan);
  for (auto& [t, i] : byTask) {
    std::vector<uint32_t> expect;
    for (uint32_t u = tasks[t].begin; u < tasks[t].end; ++u) expect.push_back(u);
    if (loaded[i].result.units != expect)
      throw std::runtime_error(fmt::format("merge: {}: task {} holds units {} but the plan says {}", parts[i], t,
                                           unitList(loaded[i].result.units), unitList(expect)));
    merged.add(loaded[i].result);
  }
  writeFinalImages(exrPath, pngPath, first.id, first.plan, merged);
}

}  // namespace mlt::farm
