// Wire <-> domain conversion with range validation (see convert.h).
#include "proto/convert.h"
#include "proto/sparse_film.h"

#include "common/methods/registry.h"
#include "common/settings/direct_light_name.h"
#include "common/settings/mis_heuristic_name.h"
#include "common/settings/splatting_name.h"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <fmt/format.h>

namespace mlt::wire {
namespace {

static_assert(std::endian::native == std::endian::little, "film bytes are little-endian");

constexpr int64_t kMaxFilmSide = 16384;
constexpr double kMaxMutationsPerPixel = 1e6;
constexpr int64_t kMaxSpp = 1 << 20;
constexpr int64_t kMaxChains = 1 << 20;
constexpr int64_t kMaxBootstrap = 100'000'000;
constexpr int64_t kMaxDepth = 1024;

void requireRange(const char* field, int64_t v, int64_t lo, int64_t hi) {
  if (v < lo || v > hi) throw WireError(field, fmt::format("{} is out of range [{}, {}]", v, lo, hi));
}
void requireRange(const char* field, double v, double lo, double hi, bool loOpen = false) {
  if (!std::isfinite(v) || v > hi || v < lo || (loOpen && v == lo))
    throw WireError(field, fmt::format("{} is out of range {}{}, {}]", v, loOpen ? "(" : "[", lo, hi));
}


}  // namespace

std::string deterministicBytes(const google::protobuf::MessageLite& m) {
  std::string out;
  {
    google::protobuf::io::StringOutputStream sos(&out);
    google::protobuf::io::CodedOutputStream cos(&sos);
    cos.SetSerializationDeterministic(true);
    m.SerializeToCodedStream(&cos);
  }
  return out;
}

void checkVersion(uint32_t version, const char* message) {
  if (version != kFormatVersion)
    throw WireError(std::string(message) + ".format_version",
                    fmt::format("peer speaks format version {}, this build speaks {}", version, kFormatVersion));
}

void validateDefines(const std::map<std::string, std::string>& defines, const char* field) {
  if (defines.size() > 256) throw WireError(field, fmt::format("{} defines (at most 256)", defines.size()));
  for (const auto& [name, value] : defines) {
    const bool ok = !name.empty() && name.size() <= 128 && std::all_of(name.begin(), name.end(), [](char c) {
      return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    });
    if (!ok) throw WireError(field, fmt::format("name '{}' must be 1-128 letters, digits or '_'", name));
    if (value.size() > 4096 || value.find('\0') != std::string::npos)
      throw WireError(field, fmt::format("value of '{}' is longer than 4096 bytes or contains NUL", name));
  }
}

// ---------------------------------------------------------------------------------------------
// Settings
// ---------------------------------------------------------------------------------------------
v1::RenderSettings toProto(const RenderSettings& s) { return toProto(SubmittedSettings{s, true, true, true, true, {}}); }

v1::RenderSettings toProto(const SubmittedSettings& sub) {
  const RenderSettings& s = sub.settings;
  const bool hasSize = sub.hasSize, hasMaxDepth = sub.hasMaxDepth, hasRrDepth = sub.hasRrDepth;
  v1::RenderSettings p;
  p.set_has_spp(sub.hasSpp);
  p.set_method(s.method);
  p.set_seed(s.seed);
  p.set_width(s.width);
  p.set_height(s.height);
  p.set_has_size(hasSize);
  p.set_max_depth(s.integrator.maxDepth);
  p.set_rr_depth(s.integrator.rrDepth);
  p.set_has_max_depth(hasMaxDepth);
  p.set_has_rr_depth(hasRrDepth);
  p.set_mis_heuristic(misHeuristicName(s.integrator.heuristic));
  v1::SampleSettings samples;
  samples.set_spp(s.spp);
  samples.set_samples_per_unit(s.samplesPerUnit);
  // A method this process does not know (the coordinator may know more) travels with sample settings;
  // the receiver names it if it does not know it either.
  if (hasMethod(s.method) && isMarkovChainMethod(s.method)) {
    v1::ChainSettings* c = p.mutable_chains();
    c->set_mutations_per_pixel(s.mutationsPerPixel);
    c->set_chains(s.chains);
    c->set_bootstrap_samples(s.bootstrapSamples);
    c->set_large_step_prob(s.largeStepProb);
    c->set_kernel(s.kernel == MutationKernel::Kelemen ? "kelemen" : "gaussian");
    c->set_kelemen_s1(s.kelemenS1);
    c->set_kelemen_s2(s.kelemenS2);
    c->set_gaussian_sigma(s.gaussianSigma);
    c->set_splatting(splattingName(s.splatting));  // "": the method's
    c->set_direct_light(directLightName(s.directLight));
    c->set_separate_direct(s.directLight == DirectLight::Separate);  // for readers before direct_light
    *c->mutable_direct() = samples;
  } else {
    *p.mutable_samples() = samples;
  }
  for (const auto& [name, value] : s.params) (*p.mutable_params())[name] = value;
  for (const auto& [name, value] : sub.defines) (*p.mutable_defines())[name] = value;
  return p;
}

SubmittedSettings fromProto(const v1::RenderSettings& p) {
  SubmittedSettings out;
  RenderSettings& s = out.settings;
  try {
    findMethod(p.method());  // a registered method
    s.method = p.method();
  } catch (const std::exception& e) {
    throw WireError("settings.method", e.what());
  }
  s.seed = p.seed();
  out.hasSize = p.has_size();
  out.hasSpp = p.has_spp();
  if (p.has_size()) {
    requireRange("settings.width", p.width(), 1, kMaxFilmSide);
    requireRange("settings.height", p.height(), 1, kMaxFilmSide);
    s.width = int(p.width());
    s.height = int(p.height());
  } else if (p.width() != 0 || p.height() != 0) {
    throw WireError("settings.has_size", "width/height given without has_size");
  }
  out.hasMaxDepth = p.has_max_depth();
  if (p.has_max_depth()) {
    requireRange("settings.max_depth", p.max_depth(), -1, kMaxDepth);
    s.integrator.maxDepth = int(p.max_depth());
  }
  out.hasRrDepth = p.has_rr_depth();
  if (p.has_rr_depth()) {
    requireRange("settings.rr_depth", p.rr_depth(), 0, kMaxDepth);
    s.integrator.rrDepth = int(p.rr_depth());
  }
  if (p.mis_heuristic().empty()) s.integrator.heuristic = MisHeuristic::Power;  // a writer that did not set it
  else if (const std::optional<MisHeuristic> h = misHeuristicFromName(p.mis_heuristic())) s.integrator.heuristic = *h;
  else throw WireError("settings.mis_heuristic", fmt::format("unknown '{}' (balance|power)", p.mis_heuristic()));
  // The family's settings: exactly the group the method reads (the oneof), checked against the method.
  const bool chainMethod = isMarkovChainMethod(s.method);
  if (chainMethod && !p.has_chains())
    throw WireError("settings.chains", fmt::format("method {} needs chain settings", s.method));
  if (!chainMethod && !p.has_samples())
    throw WireError("settings.samples", fmt::format("method {} needs sample settings", s.method));
  const v1::SampleSettings& samples = chainMethod ? p.chains().direct() : p.samples();
  const std::string sp = chainMethod ? "settings.chains.direct" : "settings.samples";
  if (chainMethod) {
    // "": a writer before direct_light, whose separate_direct said separate or not (auto is new).
    const std::string& name = p.chains().direct_light();
    const std::optional<DirectLight> d =
        name.empty() ? std::optional(p.chains().separate_direct() ? DirectLight::Separate : DirectLight::Auto)
                     : directLightFromName(name);
    if (!d) throw WireError("settings.chains.direct_light", fmt::format("unknown '{}' (auto|chains|separate|emission)", name));
    s.directLight = *d;
  }
  if (!chainMethod || samples.spp() != 0) {
    requireRange((sp + ".spp").c_str(), samples.spp(), 1, kMaxSpp);
    s.spp = int(samples.spp());
  } else if (separatesDirect(s)) {
    s.spp = 0;  // the direct pass sized by the plan (directSppFor)
  }
  requireRange((sp + ".samples_per_unit").c_str(), samples.samples_per_unit(), 0, kMaxSpp);
  s.samplesPerUnit = int(samples.samples_per_unit());
  if (chainMethod) {
    const v1::ChainSettings& c = p.chains();
    requireRange("settings.chains.mutations_per_pixel", c.mutations_per_pixel(), 0.0, kMaxMutationsPerPixel, true);
    s.mutationsPerPixel = c.mutations_per_pixel();
    requireRange("settings.chains.chains", c.chains(), 0, kMaxChains);
    s.chains = int(c.chains());
    requireRange("settings.chains.bootstrap_samples", c.bootstrap_samples(), 0, kMaxBootstrap);  // 0 = automatic
    s.bootstrapSamples = int(c.bootstrap_samples());
    // Negative: the method's default (RenderSettings::largeStepProb), resolved by the plan.
    if (!(c.large_step_prob() < 0)) requireRange("settings.chains.large_step_prob", c.large_step_prob(), 0.0, 1.0);
    s.largeStepProb = c.large_step_prob() < 0 ? -1.0f : float(c.large_step_prob());
    if (c.kernel() == "kelemen" || c.kernel().empty()) s.kernel = MutationKernel::Kelemen;
    else if (c.kernel() == "gaussian") s.kernel = MutationKernel::Gaussian;
    else throw WireError("settings.chains.kernel", fmt::format("unknown '{}' (kelemen|gaussian)", c.kernel()));
    requireRange("settings.chains.kelemen_s1", c.kelemen_s1(), 0.0, 1.0, true);
    requireRange("settings.chains.kelemen_s2", c.kelemen_s2(), c.kelemen_s1(), 1.0);
    requireRange("settings.chains.gaussian_sigma", c.gaussian_sigma(), 0.0, 1.0, true);
    s.kelemenS1 = float(c.kelemen_s1());
    s.kelemenS2 = float(c.kelemen_s2());
    s.gaussianSigma = float(c.gaussian_sigma());
    const std::optional<MltSplatting> splatting = splattingFromName(c.splatting());
    if (!splatting)
      throw WireError("settings.chains.splatting", fmt::format("unknown '{}' (expected-value|kelemen-mis)", c.splatting()));
    s.splatting = *splatting;
  }
  if (p.params_size() > 256) throw WireError("settings.params", "more than 256 parameters");
  for (const auto& [name, value] : p.params()) {
    if (name.size() > 128 || value.size() > 4096)
      throw WireError("settings.params", fmt::format("parameter '{}' or its value is too long", name.substr(0, 128)));
    s.params[name] = value;
  }
  try {
    findMethod(s.method).checkParams(s.params);  // names, types, ranges (the rest is checked at planning)
  } catch (const std::invalid_argument& e) {
    throw WireError("settings.params", e.what());
  }
  out.defines.insert(p.defines().begin(), p.defines().end());
  validateDefines(out.defines, "settings.defines");
  return out;
}

// ---------------------------------------------------------------------------------------------
// Plan
// ---------------------------------------------------------------------------------------------
v1::TargetSums toProto(const TargetSums& t) {
  v1::TargetSums p;
  p.set_n(t.n);
  p.set_sum(t.sum);
  p.set_sum_sq(t.sumSq);
  p.set_bulk(t.bulk);
  p.set_bulk_sq(t.bulkSq);
  p.set_excess_sq(t.excessSq);
  return p;
}

TargetSums fromProto(const v1::TargetSums& p, const char* field) {
  for (double v : {p.sum(), p.sum_sq(), p.bulk(), p.bulk_sq(), p.excess_sq()})
    if (!(std::isfinite(v) && v >= 0))
      throw WireError(field, fmt::format("sums must be finite and >= 0, got {}", v));
  TargetSums t;
  t.n = p.n();
  t.sum = p.sum();
  t.sumSq = p.sum_sq();
  t.bulk = p.bulk();
  t.bulkSq = p.bulk_sq();
  t.excessSq = p.excess_sq();
  return t;
}

v1::JobPlan toProto(const JobPlan& plan) {
  v1::JobPlan p;
  p.set_format_version(kFormatVersion);
  *p.mutable_settings() = toProto(plan.settings);
  auto* n = p.mutable_norm();
  n->set_b(plan.norm.b);
  n->set_b_std_err(plan.norm.bStdErr);
  for (double v : plan.norm.bk) n->add_bk(v);
  for (double v : plan.norm.bkStdErr) n->add_bk_std_err(v);
  for (uint64_t v : plan.norm.mutationsPerLength) n->add_mutations_per_length(v);
  n->set_total_mutations(plan.norm.totalMutations);
  n->set_bootstrap_samples(plan.norm.bootstrapSamples);
  n->set_bootstrap_samples_in_b(plan.norm.bootstrapSamplesInB);
  n->set_bootstrap_seconds(plan.norm.bootstrapSeconds);
  if (plan.norm.directShare >= 0) {
    n->set_direct_share(plan.norm.directShare);
    if (plan.norm.directCv >= 0) n->set_direct_cv(plan.norm.directCv);  // absent: the share alone decided
  }
  if (const ImportanceMap& m = plan.norm.importance; !m.empty()) {
    auto* i = n->mutable_importance();
    i->set_film_width(m.filmWidth);
    i->set_film_height(m.filmHeight);
    i->set_tile_size(m.tileSize);
    i->set_tiles_x(m.tilesX);
    i->set_tiles_y(m.tilesY);
    i->mutable_h()->Add(m.h.begin(), m.h.end());
  }
  const auto estimate = [](const BootstrapEstimate& e, v1::BootstrapEstimate* p) {
    p->set_n(e.n);
    p->set_b(e.b);
    p->set_std_err(e.stdErr);
    p->set_sample_var(e.sampleVar);
    p->set_tau(e.tau);
    p->set_bulk_b(e.bulkB);
    p->set_bulk_std_err(e.bulkStdErr);
    p->set_bulk_var(e.bulkVar);
    p->set_excess_mean_sq(e.excessMeanSq);
  };
  for (const BootstrapEstimate& e : plan.norm.bootstrapB) estimate(e, n->add_bootstrap_b());
  for (const BootstrapEstimate& e : plan.norm.bootstrapLuminance) estimate(e, n->add_bootstrap_luminance());
  if (plan.norm.targetPower != 1) n->set_target_power(plan.norm.targetPower);
  for (const WorkUnit& u : plan.units) {
    auto* w = p.add_units();
    w->set_index(u.index);
    w->set_sample_begin(u.sampleBegin);
    w->set_sample_end(u.sampleEnd);
    w->set_start_candidate(u.startCandidate);
    w->set_path_length(u.pathLength);
    w->set_mutations(u.mutations);
    w->set_start_contribution(u.startContribution);
  }
  return p;
}

JobPlan fromProto(const v1::JobPlan& p) {
  checkVersion(p.format_version(), "JobPlan");
  JobPlan plan;
  SubmittedSettings s = fromProto(p.settings());
  if (!s.hasSize) throw WireError("plan.settings.has_size", "a plan has a resolved film size");
  plan.settings = s.settings;
  const auto& n = p.norm();
  plan.norm.b = n.b();
  plan.norm.bStdErr = n.b_std_err();
  plan.norm.bk.assign(n.bk().begin(), n.bk().end());
  plan.norm.bkStdErr.assign(n.bk_std_err().begin(), n.bk_std_err().end());
  plan.norm.mutationsPerLength.assign(n.mutations_per_length().begin(), n.mutations_per_length().end());
  plan.norm.totalMutations = n.total_mutations();
  plan.norm.bootstrapSamples = n.bootstrap_samples();
  plan.norm.bootstrapSamplesInB = n.has_bootstrap_samples_in_b() ? n.bootstrap_samples_in_b() : n.bootstrap_samples();
  if (plan.norm.bootstrapSamplesInB > plan.norm.bootstrapSamples)
    throw WireError("plan.norm.bootstrap_samples_in_b",
                    fmt::format("{} exceeds bootstrap_samples {}", plan.norm.bootstrapSamplesInB, plan.norm.bootstrapSamples));
  plan.norm.bootstrapSeconds = n.bootstrap_seconds();
  if (n.has_direct_share()) {
    if (!(n.direct_share() >= 0 && n.direct_share() <= 1))
      throw WireError("plan.norm.direct_share", fmt::format("invalid value {}", n.direct_share()));
    if (n.has_direct_cv() && !(n.direct_cv() >= 0 && std::isfinite(n.direct_cv())))
      throw WireError("plan.norm.direct_cv", fmt::format("invalid value {}", n.direct_cv()));
    plan.norm.directShare = n.direct_share();
    plan.norm.directCv = n.has_direct_cv() ? n.direct_cv() : -1;
  }
  if (n.has_importance() && n.importance().h_size() > 0) {
    const auto& i = n.importance();
    ImportanceMap& m = plan.norm.importance;
    m.filmWidth = i.film_width();
    m.filmHeight = i.film_height();
    m.tileSize = i.tile_size();
    m.tilesX = i.tiles_x();
    m.tilesY = i.tiles_y();
    m.h.assign(i.h().begin(), i.h().end());
    try {
      validateImportanceMap(m, "the map");
    } catch (const std::invalid_argument& e) {
      throw WireError("plan.norm.importance", e.what());
    }
    if (m.filmWidth != plan.settings.width || m.filmHeight != plan.settings.height)
      throw WireError("plan.norm.importance", fmt::format("a map of a {}x{} film in a plan of {}x{}", m.filmWidth,
                                                          m.filmHeight, plan.settings.width, plan.settings.height));
  }
  const auto estimate = [](const v1::BootstrapEstimate& e, const std::string& field) {
    for (double v : {e.b(), e.std_err(), e.sample_var(), e.bulk_b(), e.bulk_std_err(), e.bulk_var(), e.excess_mean_sq()})
      if (!(std::isfinite(v) && v >= 0)) throw WireError(field, fmt::format("invalid value {}", v));
    if (!(e.tau() >= 0)) throw WireError(field + ".tau", fmt::format("invalid value {}", e.tau()));
    return BootstrapEstimate{e.n(), e.b(), e.std_err(), e.sample_var(), e.tau(), e.bulk_b(), e.bulk_std_err(),
                             e.bulk_var(), e.excess_mean_sq()};
  };
  for (const auto& e : n.bootstrap_b()) plan.norm.bootstrapB.push_back(estimate(e, "plan.norm.bootstrap_b"));
  for (const auto& e : n.bootstrap_luminance())
    plan.norm.bootstrapLuminance.push_back(estimate(e, "plan.norm.bootstrap_luminance"));
  if (n.has_target_power()) {
    if (!(n.target_power() > 0 && n.target_power() <= 1))
      throw WireError("plan.norm.target_power", fmt::format("invalid value {} (a power in (0, 1])", n.target_power()));
    plan.norm.targetPower = n.target_power();
  }
  if (!plan.norm.bootstrapLuminance.empty() && !plan.norm.target().shaped())
    throw WireError("plan.norm.bootstrap_luminance", "a luminance estimate without an importance map or a target power");
  if (p.total_units() != 0 && p.total_units() != uint32_t(p.units_size()))  // a page, not a whole plan
    throw WireError("plan.total_units", fmt::format("{} units in a plan of {}: a page (proto/plan_pages.h)",
                                                    p.units_size(), p.total_units()));
  plan.units.reserve(p.units_size());
  for (int i = 0; i < p.units_size(); ++i) {
    const auto& w = p.units(i);
    if (w.index() != uint32_t(i)) throw WireError("plan.units.index", fmt::format("unit {} has index {}", i, w.index()));
    if (w.path_length() < -1 || w.path_length() > kMaxDepth)  // -1: all lengths; else a length up to max depth
      throw WireError("plan.units.path_length", fmt::format("unit {}: {} outside [-1, {}]", i, w.path_length(), kMaxDepth));
    if (w.sample_begin() > w.sample_end())
      throw WireError("plan.units.sample_begin", fmt::format("unit {}: samples [{}, {})", i, w.sample_begin(), w.sample_end()));
    WorkUnit u;
    u.index = w.index();
    u.sampleBegin = w.sample_begin();
    u.sampleEnd = w.sample_end();
    u.startCandidate = w.start_candidate();
    u.pathLength = w.path_length();
    u.mutations = w.mutations();
    u.startContribution = w.start_contribution();
    plan.units.push_back(u);
  }
  return plan;
}

std::string jobPlanBytes(const JobPlan& plan) { return deterministicBytes(toProto(plan)); }

JobPlan parseJobPlan(const std::string& bytes) {
  v1::JobPlan p;
  if (!p.ParseFromString(bytes)) throw WireError("JobPlan", "unparsable bytes");
  return fromProto(p);
}

// ---------------------------------------------------------------------------------------------
// Partial results
// ---------------------------------------------------------------------------------------------
v1::ChainStats toProto(const ChainStats& s) {
  v1::ChainStats p;
  for (uint64_t v : s.proposedPerLength) p.add_proposed_per_length(v);
  for (uint64_t v : s.acceptedPerLength) p.add_accepted_per_length(v);
  for (uint64_t v : s.proposedPerKind) p.add_proposed_per_kind(v);
  for (uint64_t v : s.acceptedPerKind) p.add_accepted_per_kind(v);
  for (double v : s.secondsPerKind) p.add_seconds_per_kind(v);
  for (uint64_t v : s.proposedPerLengthKind) p.add_proposed_per_length_kind(v);
  for (uint64_t v : s.acceptedPerLengthKind) p.add_accepted_per_length_kind(v);
  for (const TargetSums& t : s.largeStepSums) *p.add_large_step_sums() = toProto(t);
  for (const TargetSums& t : s.largeStepLuminanceSums) *p.add_large_step_luminance_sums() = toProto(t);
  return p;
}

ChainStats fromProto(const v1::ChainStats& p) {
  constexpr int kMaxKinds = 64;
  ChainStats s;
  s.proposedPerLength.assign(p.proposed_per_length().begin(), p.proposed_per_length().end());
  s.acceptedPerLength.assign(p.accepted_per_length().begin(), p.accepted_per_length().end());
  if (p.proposed_per_kind_size() > kMaxKinds || p.accepted_per_kind_size() > kMaxKinds ||
      p.seconds_per_kind_size() > kMaxKinds)
    throw WireError("stats.proposed_per_kind", fmt::format("at most {} mutation kinds", kMaxKinds));
  for (double v : p.seconds_per_kind())
    if (!(v >= 0) || !std::isfinite(v)) throw WireError("stats.seconds_per_kind", fmt::format("{} is not a time", v));
  s.proposedPerKind.assign(p.proposed_per_kind().begin(), p.proposed_per_kind().end());
  s.acceptedPerKind.assign(p.accepted_per_kind().begin(), p.accepted_per_kind().end());
  s.secondsPerKind.assign(p.seconds_per_kind().begin(), p.seconds_per_kind().end());
  if (p.proposed_per_length_kind_size() % ChainStats::kKindStride != 0 ||
      p.accepted_per_length_kind_size() > p.proposed_per_length_kind_size() ||
      p.proposed_per_length_kind_size() > p.proposed_per_length_size() * int(ChainStats::kKindStride))
    throw WireError("stats.proposed_per_length_kind",
                    fmt::format("{} values for {} path lengths: {} per length expected", p.proposed_per_length_kind_size(),
                                p.proposed_per_length_size(), ChainStats::kKindStride));
  s.proposedPerLengthKind.assign(p.proposed_per_length_kind().begin(), p.proposed_per_length_kind().end());
  s.acceptedPerLengthKind.assign(p.accepted_per_length_kind().begin(), p.accepted_per_length_kind().end());
  for (const auto& t : p.large_step_sums()) s.largeStepSums.push_back(fromProto(t, "stats.large_step_sums"));
  for (const auto& t : p.large_step_luminance_sums())
    s.largeStepLuminanceSums.push_back(fromProto(t, "stats.large_step_luminance_sums"));
  return s;
}

size_t filmByteSize(int width, int height, size_t splatLayers) {
  return size_t(width) * size_t(height) * (4 + 3 * splatLayers) * sizeof(double);
}

std::string encodeFilm(const Film& film) {
  static_assert(sizeof(RGBd) == 3 * sizeof(double));
  const size_t n = film.pixelCount();
  const std::vector<uint32_t> layers = film.splatLayers();
  std::string out(filmByteSize(film.width(), film.height(), layers.size()), '\0');
  char* dst = out.data();
  if (n) {
    std::memcpy(dst, film.pixelSums().data(), n * sizeof(RGBd));
    dst += n * sizeof(RGBd);
    std::memcpy(dst, film.pixelCounts().data(), n * sizeof(double));
    dst += n * sizeof(double);
    for (uint32_t l : layers) {
      std::memcpy(dst, film.splatLayer(l).data(), n * sizeof(RGBd));
      dst += n * sizeof(RGBd);
    }
  }
  return out;
}

namespace {
void checkFilmShape(int width, int height, const std::vector<uint32_t>& layers) {
  if (width <= 0 || height <= 0 || width > kMaxFilmSide || height > kMaxFilmSide)
    throw WireError("partial.width", fmt::format("film {}x{} out of range", width, height));
  if (layers.empty() || layers[0] != 0) throw WireError("partial.splat_layers", "must start with layer 0");
  for (size_t i = 1; i < layers.size(); ++i)
    if (layers[i] <= layers[i - 1] || layers[i] > kMaxSplatLayer)
      throw WireError("partial.splat_layers", fmt::format("layers must ascend and be at most {}, got {} after {}",
                                                          kMaxSplatLayer, layers[i], layers[i - 1]));
}

// A zero film with those layers, its shape already checked.
Film allocateFilm(int width, int height, uint64_t nonFinite, const std::vector<uint32_t>& layers) {
  Film film(width, height);
  for (uint32_t l : layers) film.splatLayer(l);
  film.setNonFiniteSamples(nonFinite);
  return film;
}
}  // namespace

Film zeroFilm(int width, int height, uint64_t nonFinite, const std::vector<uint32_t>& layers) {
  checkFilmShape(width, height, layers);
  return allocateFilm(width, height, nonFinite, layers);
}

Film decodeFilm(int width, int height, const std::string& bytes, uint64_t nonFinite,
                const std::vector<uint32_t>& layers) {
  checkFilmShape(width, height, layers);
  const size_t expected = filmByteSize(width, height, layers.size());
  if (bytes.size() != expected)
    throw WireError("film_chunk", fmt::format("film {}x{} with {} splat layers needs {} bytes, got {}", width, height,
                                              layers.size(), expected, bytes.size()));
  Film film = allocateFilm(width, height, nonFinite, layers);
  const size_t n = film.pixelCount();
  const char* src = bytes.data();
  std::memcpy(film.pixelSums().data(), src, n * sizeof(RGBd));
  src += n * sizeof(RGBd);
  std::memcpy(film.pixelCounts().data(), src, n * sizeof(double));
  src += n * sizeof(double);
  for (uint32_t l : layers) {
    std::memcpy(film.splatLayer(l).data(), src, n * sizeof(RGBd));
    src += n * sizeof(RGBd);
  }
  return film;
}

v1::PartialHeader partialHeader(const PartialResult& r) {
  // What goes on the wire is a merged result (a task's, or a job's): its splats are all in `film`. A unit's
  // pending sparse splats here would be lost, so refuse rather than send a film without them.
  if (!r.splats.empty())
    throw std::logic_error("partialHeader: the result still holds sparse splats; fold them (PartialResult::foldSplats) first");
  v1::PartialHeader h;
  h.set_format_version(kFormatVersion);
  h.set_width(r.film.width());
  h.set_height(r.film.height());
  h.set_samples(r.samples);
  *h.mutable_stats() = toProto(r.stats);
  for (uint32_t u : r.units) h.add_units(u);
  h.set_seconds(r.seconds);
  h.set_non_finite(r.film.nonFiniteSamples());
  const std::vector<uint32_t> layers = r.film.splatLayers();
  for (uint32_t l : layers) h.add_splat_layers(l);
  h.set_film_bytes(filmByteSize(r.film.width(), r.film.height(), layers.size()));
  return h;
}

std::vector<uint32_t> headerLayers(const v1::PartialHeader& h) {
  std::vector<uint32_t> layers(h.splat_layers().begin(), h.splat_layers().end());
  if (layers.empty()) layers.push_back(0);  // a header without the field: the one splat layer
  return layers;
}

PartialResult fromProto(const v1::PartialHeader& h, const std::string& filmBytes) {
  checkVersion(h.format_version(), "PartialHeader");
  PartialResult r;
  if (h.film_encoding() == v1::FILM_ZERO_RUNS)
    r.film = decodeFilmZeroRuns(h.width(), h.height(), filmBytes, h.non_finite(), headerLayers(h));
  else if (h.film_encoding() == v1::FILM_RAW)
    r.film = decodeFilm(h.width(), h.height(), filmBytes, h.non_finite(), headerLayers(h));
  else
    throw WireError("partial.film_encoding", fmt::format("unknown encoding {}", int(h.film_encoding())));
  r.samples = h.samples();
  r.stats = fromProto(h.stats());
  r.units.assign(h.units().begin(), h.units().end());
  r.seconds = h.seconds();
  return r;
}

std::string partialHeaderBytes(const PartialResult& r) { return deterministicBytes(partialHeader(r)); }

PartialResult partialFromHeaderBytes(const std::string& headerBytes, Film film) {
  v1::PartialHeader h;
  if (!h.ParseFromString(headerBytes)) throw WireError("partial", "unparsable header");
  checkVersion(h.format_version(), "PartialHeader");
  if (h.width() != film.width() || h.height() != film.height())
    throw WireError("partial.width", fmt::format("header says {}x{}, the film is {}x{}", h.width(), h.height(),
                                                 film.width(), film.height()));
  if (headerLayers(h) != film.splatLayers())
    throw WireError("partial.splat_layers", "the header's splat layers differ from the film's");
  PartialResult r;
  r.film = std::move(film);
  r.samples = h.samples();
  r.stats = fromProto(h.stats());
  r.units.assign(h.units().begin(), h.units().end());
  r.seconds = h.seconds();
  return r;
}

std::string serializePartial(const PartialResult& r, bool zeroRuns) {
  v1::PartialHeader h = partialHeader(r);
  std::string film = zeroRuns ? encodeFilmZeroRuns(r.film) : encodeFilm(r.film);
  if (zeroRuns) {
    h.set_film_encoding(v1::FILM_ZERO_RUNS);
    h.set_film_bytes(film.size());
  }
  std::string header = deterministicBytes(h);
  std::string out(8, '\0');
  uint64_t len = header.size();
  std::memcpy(out.data(), &len, 8);
  out.reserve(8 + header.size() + film.size());
  out += header;
  out += film;
  return out;
}

PartialResult parsePartial(const std::string& blob) {
  uint64_t len = 0;
  if (blob.size() < 8) throw WireError("partial", "blob too short");
  std::memcpy(&len, blob.data(), 8);
  if (len > blob.size() - 8) throw WireError("partial", "header length beyond blob");
  v1::PartialHeader h;
  if (!h.ParseFromArray(blob.data() + 8, int(len))) throw WireError("partial", "unparsable header");
  return fromProto(h, blob.substr(8 + len));
}

}  // namespace mlt::wire
