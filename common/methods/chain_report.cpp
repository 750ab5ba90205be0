#include "common/methods/chain_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "common/job/mlt_job.h"
#include "common/methods/pss_method.h"
#include "common/methods/registry.h"
#include "common/settings/direct_light_name.h"
#include "common/settings/splatting_name.h"

namespace mlt {

namespace {

double ratio(uint64_t a, uint64_t b) { return b > 0 ? double(a) / double(b) : 0.0; }

// "b<k>" -> k (digits only after the prefix), else -1.
int lengthOfKey(const std::string& key, const std::string& prefix) {
  if (key.size() <= prefix.size() || key.compare(0, prefix.size(), prefix) != 0) return -1;
  int k = 0;
  for (size_t i = prefix.size(); i < key.size(); ++i) {
    if (key[i] < '0' || key[i] > '9' || k > 100000) return -1;
    k = 10 * k + (key[i] - '0');
  }
  return k;
}

std::string capitalized(std::string s) {
  if (!s.empty() && s[0] >= 'a' && s[0] <= 'z') s[0] = char(s[0] - 'a' + 'A');
  return s;
}

double number(const ImageMetadata& m, const std::string& key) {
  const auto it = m.numbers.find(key);
  return it == m.numbers.end() ? 0.0 : it->second;
}

}  // namespace

uint64_t ChainReport::steps(const std::string& kind) const {
  for (const MutationKindReport& k : kinds)
    if (k.name == kind) return k.proposed;
  return 0;
}

double ChainReport::acceptanceOf(const std::string& kind) const {
  for (const MutationKindReport& k : kinds)
    if (k.name == kind) return k.acceptance;
  return 0;
}

ChainReport::CrowdedStart crowdedStart(const JobPlan& plan) {
  std::map<std::pair<int, uint64_t>, uint64_t> onStart;  // (path length, start candidate) -> chains
  std::map<int, uint64_t> perLength;
  for (const WorkUnit& u : plan.units)
    if (u.mutations > 0) {
      ++onStart[{u.pathLength, u.startCandidate}];
      ++perLength[u.pathLength];
    }
  ChainReport::CrowdedStart worst;
  double worstShare = 0;
  for (const auto& [key, chains] : onStart) {
    const uint64_t of = perLength[key.first];
    const double share = double(chains) / double(of);
    if (chains >= kCrowdedStartChains && share >= kCrowdedStartShare && share > worstShare) {
      worstShare = share;
      worst = {key.first, chains, of, key.second};
    }
  }
  return worst;
}

ChainReport makeChainReport(const JobPlan& plan, const PartialResult& merged) {
  const RenderSettings& s = plan.settings;
  const Normalization& norm = plan.norm;
  ChainReport r;
  r.method = s.method;
  r.settings = s;
  // b as developed: pooled from the bootstrap and the large steps merged (develop.h (D3), (D4)); with a
  // relative or tempered target the image's brightness, b_lum, to which each length's image is scaled (D8).
  const bool shaped = norm.target().shaped();
  const RefinedB refined = shaped ? refinedLuminanceB(norm, merged.stats) : refinedB(norm, merged.stats, &merged.film);
  r.b = refined.total.b;
  r.bStdErr = refined.total.stdErr;
  r.bBootstrap = norm.b;
  r.bBootstrapStdErr = norm.bStdErr;
  if (shaped) {  // the bootstrap's b_lum alone: no large steps pooled
    const BEstimate boot = refinedLuminanceB(norm, ChainStats{}).total;
    r.bBootstrap = boot.b;
    r.bBootstrapStdErr = boot.stdErr;
  }
  r.directShare = norm.directShare;
  r.directCv = norm.directCv;
  r.bootstrapSamples = norm.bootstrapSamples;
  r.bootstrapSamplesInB = norm.bootstrapSamplesInB;
  for (const TargetSums& l : merged.stats.largeStepSums) r.bSamples += l.n;  // the independent proposals
  r.bSamples += norm.bootstrapSamplesInB;
  if (const ChainJobSpec* spec = findChainJobSpec(s.method); spec && spec->chainsPerLength())
    for (size_t k = 0; k < norm.mutationsPerLength.size(); ++k)
      if (norm.mutationsPerLength[k] > 0) r.bSampleEvery = std::max(r.bSampleEvery, bSampleStride(*spec, s, norm, int(k)));
  r.mutations = merged.samples;
  r.crowdedStart = crowdedStart(plan);
  r.mutationsPerPixel = s.mutationsPerPixel;
  r.hasAcceptance = true;
  const std::vector<std::string>& names = mutationKindNames(s.method);
  uint64_t proposed = 0, accepted = 0;
  for (size_t k = 0; k < names.size(); ++k) {
    const auto& P = merged.stats.proposedPerKind;
    const auto& A = merged.stats.acceptedPerKind;
    const auto& S = merged.stats.secondsPerKind;
    MutationKindReport kind{names[k], k < P.size() ? P[k] : 0, 0.0, k < S.size() ? S[k] : 0.0};
    kind.acceptance = ratio(k < A.size() ? A[k] : 0, kind.proposed);
    proposed += kind.proposed;
    accepted += k < A.size() ? A[k] : 0;
    r.kinds.push_back(kind);
  }
  r.acceptance = ratio(accepted, proposed);

  // Chains merged, per path length (units of a separateDirect direct pass have no mutations).
  std::vector<uint64_t> chainsPerSlot(std::max<size_t>(norm.mutationsPerLength.size(), 1), 0);
  for (uint32_t i : merged.units) {
    if (i >= plan.units.size() || plan.units[i].mutations == 0) continue;
    const size_t slot = size_t(std::max(plan.units[i].pathLength, 0));
    if (slot >= chainsPerSlot.size()) chainsPerSlot.resize(slot + 1, 0);
    ++chainsPerSlot[slot];
    ++r.chains;
  }
  const PrimarySampleChainMethod* method = findPrimarySampleChainMethod(s.method);
  if (method && method->chainsPerLength()) {
    const auto& proposed = merged.stats.proposedPerLength;
    const auto& accepted = merged.stats.acceptedPerLength;
    for (int k = chainMinLength(s); k < int(norm.bk.size()); ++k) {
      ChainLengthReport l;
      l.k = k;
      l.bk = size_t(k) < refined.perSlot.size() ? refined.perSlot[size_t(k)].b : 0.0;
      l.bkStdErr = size_t(k) < refined.perSlot.size() ? refined.perSlot[size_t(k)].stdErr : 0.0;
      l.chains = size_t(k) < chainsPerSlot.size() ? chainsPerSlot[size_t(k)] : 0;
      l.mutations = size_t(k) < proposed.size() ? proposed[size_t(k)] : 0;
      l.acceptance = ratio(size_t(k) < accepted.size() ? accepted[size_t(k)] : 0, l.mutations);
      const auto& PK = merged.stats.proposedPerLengthKind;
      const auto& AK = merged.stats.acceptedPerLengthKind;
      for (size_t kind = 0; kind < names.size(); ++kind) {
        const size_t i = size_t(k) * ChainStats::kKindStride + kind;
        const uint64_t p = i < PK.size() ? PK[i] : 0;
        l.kinds.push_back({p, ratio(i < AK.size() ? AK[i] : 0, p)});
      }
      r.lengths.push_back(l);
    }
  }
  return r;
}

void addChainMetadata(const ChainReport& r, ImageMetadata& m) {
  m.numbers["b"] = r.b;
  m.numbers["bStdErr"] = r.bStdErr;
  m.numbers["bootstrapSamples"] = double(r.bootstrapSamples);
  m.numbers["bootstrapSamplesInB"] = double(r.bootstrapSamplesInB);
  m.numbers["bBootstrap"] = r.bBootstrap;
  m.numbers["bBootstrapStdErr"] = r.bBootstrapStdErr;
  m.numbers["bSamples"] = double(r.bSamples);
  if (r.bSampleEvery > 0) m.numbers["bSampleEvery"] = double(r.bSampleEvery);
  if (r.crowdedStart.chains > 0) {
    m.numbers["crowdedStartLength"] = r.crowdedStart.k;
    m.numbers["crowdedStartChains"] = double(r.crowdedStart.chains);
    m.numbers["crowdedStartOf"] = double(r.crowdedStart.of);
    m.numbers["crowdedStartCandidate"] = double(r.crowdedStart.candidate);
  }
  m.numbers["bootstrapPerLength"] = double(r.settings.bootstrapSamples);
  m.numbers["chains"] = double(r.chains);
  m.numbers["mutations"] = double(r.mutations);
  m.numbers["mutationsPerPixel"] = r.mutationsPerPixel;
  m.numbers["acceptance"] = r.acceptance;
  std::string kindList;
  for (const MutationKindReport& k : r.kinds) {
    kindList += (kindList.empty() ? "" : ",") + k.name;
    m.numbers[k.name + "Steps"] = double(k.proposed);
    m.numbers["acceptance" + capitalized(k.name)] = k.acceptance;
  }
  if (!r.kinds.empty()) m.strings["mutationKinds"] = kindList;
  const RenderSettings& s = r.settings;
  m.numbers["largeStepProb"] = s.largeStepProb;
  m.numbers["separateDirect"] = s.directLight == DirectLight::Separate ? 1 : 0;  // as files before "directLight" say
  m.strings["directLight"] = directLightName(s.directLight);
  if (separatesDirect(s)) m.numbers["directSpp"] = s.spp;  // the pass's samples per pixel
  if (r.directShare >= 0) {  // the plan chose it (--direct-light auto): what the pilot measured
    m.numbers["directLightShare"] = r.directShare;
    if (r.directCv >= 0) m.numbers["directLightCv"] = r.directCv;  // not measured below the share's threshold
  }
  m.strings["kernel"] = s.kernel == MutationKernel::Gaussian ? "gaussian" : "kelemen";
  if (s.kernel == MutationKernel::Gaussian) {
    m.numbers["kernelSigma"] = s.gaussianSigma;
  } else {
    m.numbers["kernelS1"] = s.kelemenS1;
    m.numbers["kernelS2"] = s.kelemenS2;
  }
  const std::string splatting = splattingName(s.splatting);
  m.strings["splatting"] = splatting.empty() ? "method-default" : splatting;  // empty: an unplanned job
  for (const ChainLengthReport& l : r.lengths) {
    const std::string k = std::to_string(l.k);
    m.numbers["b" + k] = l.bk;
    m.numbers["bStdErr" + k] = l.bkStdErr;
    m.numbers["chains" + k] = double(l.chains);
    m.numbers["mutations" + k] = double(l.mutations);
    m.numbers["acceptance" + k] = l.acceptance;
    for (size_t kind = 0; kind < l.kinds.size() && kind < r.kinds.size(); ++kind) {
      if (l.kinds[kind].first == 0) continue;  // e.g. no technique change at length 1 (one technique)
      m.numbers[r.kinds[kind].name + "Steps" + k] = double(l.kinds[kind].first);
      m.numbers["acceptance" + capitalized(r.kinds[kind].name) + k] = l.kinds[kind].second;
    }
  }
}

void addMoveSecondsMetadata(const ChainReport& r, ImageMetadata& m) {
  for (const MutationKindReport& k : r.kinds)
    if (k.seconds > 0) m.numbers[k.name + "Seconds"] = k.seconds;
}

ChainReport chainReportFromMetadata(const ImageMetadata& m) {
  ChainReport r;
  if (const auto it = m.strings.find("method"); it != m.strings.end()) r.method = it->second;
  r.b = number(m, "b");
  r.bStdErr = number(m, "bStdErr");
  r.bootstrapSamples = uint64_t(number(m, "bootstrapSamples"));
  // An image from before the key: b held every candidate.
  r.bootstrapSamplesInB = m.numbers.count("bootstrapSamplesInB") ? uint64_t(number(m, "bootstrapSamplesInB"))
                                                                 : r.bootstrapSamples;
  r.bSampleEvery = m.numbers.count("bSampleEvery") ? uint64_t(number(m, "bSampleEvery")) : 0;
  if (m.numbers.count("crowdedStartChains")) {
    r.crowdedStart.k = int(number(m, "crowdedStartLength"));
    r.crowdedStart.chains = uint64_t(number(m, "crowdedStartChains"));
    r.crowdedStart.of = uint64_t(number(m, "crowdedStartOf"));
    r.crowdedStart.candidate = uint64_t(number(m, "crowdedStartCandidate"));
  }
  r.bBootstrap = number(m, "bBootstrap");
  r.bBootstrapStdErr = number(m, "bBootstrapStdErr");
  if (m.numbers.count("directLightShare")) {
    r.directShare = number(m, "directLightShare");
    if (m.numbers.count("directLightCv")) r.directCv = number(m, "directLightCv");
  }
  r.bSamples = uint64_t(number(m, "bSamples"));
  r.settings.bootstrapSamples = int(number(m, "bootstrapPerLength"));
  r.chains = uint64_t(number(m, "chains"));
  r.mutations = uint64_t(number(m, "mutations"));
  r.mutationsPerPixel = number(m, "mutationsPerPixel");
  r.hasAcceptance = m.numbers.count("acceptance") > 0;
  r.acceptance = number(m, "acceptance");
  std::string kindList;
  if (const auto it = m.strings.find("mutationKinds"); it != m.strings.end()) kindList = it->second;
  else if (m.numbers.count("largeSteps")) kindList = "large,small";  // images written before the kinds were named
  for (size_t at = 0; !kindList.empty() && at <= kindList.size();) {
    const size_t comma = std::min(kindList.find(',', at), kindList.size());
    const std::string name = kindList.substr(at, comma - at);
    r.kinds.push_back({name, uint64_t(number(m, name + "Steps")), number(m, "acceptance" + capitalized(name)),
                       number(m, name + "Seconds")});
    at = comma + 1;
  }
  if (const auto it = m.numbers.find("largeStepProb"); it != m.numbers.end()) r.settings.largeStepProb = float(it->second);
  r.settings.directLight = number(m, "separateDirect") != 0 ? DirectLight::Separate : DirectLight::Chains;
  if (const auto it = m.strings.find("directLight"); it != m.strings.end())
    if (const std::optional<DirectLight> d = directLightFromName(it->second)) r.settings.directLight = *d;
  if (m.numbers.count("directSpp")) r.settings.spp = int(number(m, "directSpp"));
  if (const auto it = m.strings.find("kernel"); it != m.strings.end() && it->second == "gaussian") {
    r.settings.kernel = MutationKernel::Gaussian;
    r.settings.gaussianSigma = float(number(m, "kernelSigma"));
  } else if (m.numbers.count("kernelS1")) {
    r.settings.kelemenS1 = float(number(m, "kernelS1"));
    r.settings.kelemenS2 = float(number(m, "kernelS2"));
  }
  if (const auto it = m.strings.find("splatting"); it != m.strings.end())
    r.settings.splatting = splattingFromName(it->second).value_or(MltSplatting::MethodDefault);
  for (const auto& [key, value] : m.numbers) {
    const int k = lengthOfKey(key, "b");
    const std::string ks = std::to_string(k);
    if (k < 0 || m.numbers.count("mutations" + ks) == 0) continue;  // an image without the per-length keys
    ChainLengthReport l;
    l.k = k;
    l.bk = value;
    l.bkStdErr = number(m, "bStdErr" + ks);
    l.chains = uint64_t(number(m, "chains" + ks));
    l.mutations = uint64_t(number(m, "mutations" + ks));
    l.acceptance = number(m, "acceptance" + ks);
    for (const MutationKindReport& kind : r.kinds)
      l.kinds.push_back({uint64_t(number(m, kind.name + "Steps" + ks)), number(m, "acceptance" + capitalized(kind.name) + ks)});
    r.lengths.push_back(l);
  }
  std::sort(r.lengths.begin(), r.lengths.end(), [](const auto& a, const auto& b) { return a.k < b.k; });
  return r;
}

std::string formatChainSummary(const ChainReport& r, double bootstrapSeconds, double chainSeconds,
                               const std::string& secondsNote) {
  std::string out = fmt::format("b = {:.6g} ± {:.3g} (rel. {:.3f}%, from {} samples: {} bootstrap candidates", r.b,
                                r.bStdErr, 100 * r.relativeStdErr(), r.bSamples, r.bootstrapSamplesInB);
  if (r.bootstrapSamplesInB < r.bootstrapSamples)  // bootstrap.h, fixedCount
    out += fmt::format(" (of {} drawn: the others only seed and allocate the chains)", r.bootstrapSamples);
  out += bootstrapSeconds >= 0 ? fmt::format(" in {:.2f} s", bootstrapSeconds) : "";
  if (r.bSamples <= r.bootstrapSamplesInB)
    out += "; none from the chains)\n";
  else
    out += r.bSampleEvery > 0 ? fmt::format(" + the chains' b samples, every technique of a length at one fresh point "
                                            "per {} mutations)\n", r.bSampleEvery)
           : r.steps("large") > 0 ? " + the chains' large steps)\n" : " + the chains' independent samples)\n";
  if (!r.lengths.empty()) {
    out += fmt::format("  {:>3}  {:>25}  {:>7}  {:>12}  {:>10}  {}\n", "k", "b_k ± SE", "chains", "mutations",
                       "acceptance", "by kind");
    for (const ChainLengthReport& l : r.lengths) {
      std::string byKind;
      for (size_t kind = 0; kind < l.kinds.size() && kind < r.kinds.size(); ++kind)
        if (l.kinds[kind].first > 0)
          byKind += fmt::format("{}{} {:.1f}%", byKind.empty() ? "" : ", ", r.kinds[kind].name, 100 * l.kinds[kind].second);
      out += fmt::format("  {:>3}  {:>25}  {:>7}  {:>12}  {:>9.1f}%  {}\n", l.k,
                         fmt::format("{:.6g} ± {:.2g}", l.bk, l.bkStdErr), l.chains, l.mutations, 100 * l.acceptance,
                         byKind);
    }
  }
  if (r.hasAcceptance) {
    std::string kinds;
    for (const MutationKindReport& k : r.kinds)
      kinds += fmt::format("{}{} steps {:.1f}%", kinds.empty() ? "" : ", ", k.name, 100 * k.acceptance);
    out += fmt::format("acceptance {:.1f}% ({})\n", 100 * r.acceptance, kinds);
  }
  if (separatesDirect(r.settings) || r.directShare >= 0) {
    const std::string cv = r.directCv >= 0 ? fmt::format("CV {:.2f}", r.directCv) : std::string("CV not measured");
    const std::string pilot = r.directShare >= 0
                                  ? fmt::format("the pilot's choice: {:.1f}% of the light, {}", 100 * r.directShare, cv)
                                  : std::string("as asked");
    out += r.settings.directLight == DirectLight::Emission
               ? fmt::format("direct light (paths of at most {} segments): the lights seen directly by a {} pass of {} "
                             "samples per pixel, one bounce in the chains ({})\n",
                             kDirectMaxSegments, kDirectPassMethod, r.settings.spp,
                             r.directShare >= 0 ? pilot + "; a small light on the film" : pilot)
           : separatesDirect(r.settings)
               ? fmt::format("direct light (paths of at most {} segments): a {} pass of {} samples per pixel ({})\n",
                             kDirectMaxSegments, kDirectPassMethod, r.settings.spp, pilot)
               : fmt::format("direct light (paths of at most {} segments): in the chains ({})\n", kDirectMaxSegments,
                             pilot);
  }
  const std::string rates = formatMoveRates(r);
  if (!rates.empty()) out += fmt::format("mutations/s per move, one thread: {}\n", rates);
  // {} prints the shortest decimal that reads back as the same double: typing it reproduces the image.
  out += fmt::format("{} mutations ({} per pixel, {} chains) in {:.2f} s{} = {:.4g} mutations/s\n", r.mutations,
                     r.mutationsPerPixel, r.chains, chainSeconds, secondsNote,
                     chainSeconds > 0 ? double(r.mutations) / chainSeconds : 0.0);
  return out;
}

std::string formatMoveRates(const ChainReport& r) {
  std::string rates;
  for (const MutationKindReport& k : r.kinds)
    if (k.seconds > 0)
      rates += fmt::format("{}{} {:.4g} ({} in {:.3g} s)", rates.empty() ? "" : ", ", k.name, k.mutationsPerSecond(),
                           k.proposed, k.seconds);
  return rates;
}

std::string describeCrowdedStart(const ChainReport::CrowdedStart& c) {
  if (c.chains == 0) return "";
  return fmt::format(
      "{} of the {} chains{} start from one bootstrap candidate ({}): a path the bootstrap met far above its share, "
      "whose pixels may come out as a bright spot that the chains leave slowly (unbiased over seeds; docs/CHAINS.md, "
      "\"Crowded starts\"); each doubling of --bootstrap about halves the chains on it, another --seed draws other "
      "starts",
      c.chains, c.of, c.k >= 0 ? fmt::format(" of path length {}", c.k) : std::string(), c.candidate);
}

std::string chainWarnings(const ChainReport& r) {
  const std::string crowded =
      r.crowdedStart.chains > 0 ? "warning: " + describeCrowdedStart(r.crowdedStart) + "\n" : std::string();
  if (!(r.relativeStdErr() > kMaxRelativeStdErrB)) return crowded;
  const bool largeSteps = r.steps("large") > 0;
  const std::string remedy =
      r.bSamples > r.bootstrapSamplesInB
          ? fmt::format("render more mutations (b is refined as the chains run: now {} samples){}", r.bSamples,
                        r.bSampleEvery > 0 ? " or lower --b-sample-every" : largeSteps ? " or raise --large-step" : "")
          : fmt::format("no chain refined b, so it is the bootstrap's {} samples: render more mutations or set a "
                        "larger --bootstrap",
                        r.bootstrapSamplesInB);
  return crowded + fmt::format("warning: the relative standard error of b is {:.2f}% (> {:.0f}%), and the image's "
                               "brightness is as uncertain: {}\n",
                               100 * r.relativeStdErr(), 100 * kMaxRelativeStdErrB, remedy);
}

}  // namespace mlt
