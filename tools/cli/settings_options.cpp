// The shared render-setting options (see settings_options.h). The help texts and defaults are those
// `mltfarm render` always had; `submit` inherits them.
#include "tools/cli/settings_options.h"

#include "common/settings/direct_light_name.h"
#include "common/settings/mis_heuristic_name.h"
#include "common/settings/splatting_name.h"
#include "proto/convert.h"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

namespace mlt::cli {
namespace {

// (0, 1]: a step size in primary sample space. The wire refuses anything else (proto/convert.cpp), so the
// local farm and `submit` would fail at the coordinator naming a wire field; this names the option.
const CLI::Validator kUnitStep(
    [](std::string& value) -> std::string {
      double x = 0;
      if (!CLI::detail::lexical_cast(value, x)) return "'" + value + "' is not a number";
      return x > 0 && x <= 1 ? std::string() : "must be in (0, 1], got " + value;
    },
    "(0,1]", "UNIT_STEP");

}  // namespace

RenderSettingsOptions::RenderSettingsOptions(std::string description, std::string name, CLI::App* parent)
    : CLI::Option_group(std::move(description), std::move(name), parent) {
  std::vector<std::string> names;
  std::string methodHelp = "The rendering method:";
  for (const RenderMethod* m : allMethods()) {
    names.push_back(m->name());
    methodHelp += "\n  " + m->name() + ": " + m->description();
  }
  add_option("-m,--method", method_, methodHelp)->capture_default_str()->check(CLI::IsMember(names));
  sppOpt_ = add_option("--spp", spp_, "Samples per pixel for pt, lt (light paths = spp * pixels) and bdpt (default: the scene's sampler sample_count, else 16)")
                ->check(CLI::PositiveNumber);
  add_option("--samples-per-unit", samplesPerUnit_,
             "pt/lt/bdpt: samples per pixel in one work unit (0 = spp / 16, rounded up)")
      ->check(CLI::NonNegativeNumber);
  add_option("--mutations-per-pixel", mutationsPerPixel_, "Markov chain methods: mutations per pixel")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  add_option("--chains", chains_, "Markov chain methods: number of chains (0 = automatic)")
      ->check(CLI::NonNegativeNumber);
  add_option("--bootstrap", bootstrap_, "Markov chain methods: bootstrap size: the cost of this many of the chains' mutations per path length (a candidate's cost is counted by the numbers it draws: a long path costs more than a short one; mmlt/rjmlt's camera rays for b_1 come out of it); 0 = automatic (about 3% of the job's time: of the mutations, or of the time budget; b is refined by the chains' large steps, except veach-mlt's)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  add_option("--large-step", largeStep_,
             "Markov chain methods: large-step probability (default: the method's, 0.3; rjmlt 0.1)")
      ->check(CLI::Range(0.0, 1.0));
  add_option("--kernel", kernel_,
             "Markov chain methods: small-step kernel, kelemen (exponential, --s1/--s2) or gaussian (--sigma)")
      ->capture_default_str()
      ->check(CLI::IsMember({"kelemen", "gaussian"}));
  add_option("--s1", s1_, "Kelemen kernel: smallest step")->check(kUnitStep);
  add_option("--s2", s2_, "Kelemen kernel: largest step (at least --s1)")->check(kUnitStep);
  add_option("--sigma", sigma_, "Gaussian kernel: standard deviation")->check(kUnitStep);
  add_option("--splatting", splatting_,
             "Markov chain methods: kelemen-mis (Kelemen et al.'s large-step MIS weights; the default) or "
             "expected-value (Veach: proposal weighted by a, current state by 1 - a; veach-mlt's only)")
      ->check(CLI::IsMember({"expected-value", "kelemen-mis"}));
  CLI::Option* directLight =
      add_option("--direct-light", directLight_,
                 "pssmlt-bdpt, mmlt, rjmlt, veach-mlt: who renders paths of up to 2 segments. auto (the default): a "
                 "pilot of bdpt samples decides before the bootstrap, taking a pt pass where the direct light is "
                 "a large and smooth part of the image (docs/CHAINS.md); chains: the chains, with the rest; "
                 "separate: a pt pass (--spp samples; without --spp 0.15 s / (1 - s) per mutation per pixel, s the "
                 "pilot's share of the light in those paths, 4x that for pssmlt-bdpt, rounded up, as an automatic "
                 "pass always is) and the chains only the longer ones (Veach's refinement); emission (mmlt, rjmlt, "
                 "pssmlt-bdpt; auto takes it where a light is small on the film): a pt pass of one segment (0.125 "
                 "samples per mutation per pixel without --spp, 4x that for pssmlt-bdpt) renders the lights seen directly, the chains every longer path")
          ->capture_default_str()
          ->check(CLI::IsMember({"auto", "chains", "separate", "emission"}));
  add_flag("--separate-direct", separateDirect_, "The same as --direct-light separate")->excludes(directLight);
  add_option("--mis-heuristic", heuristic_,
             "The multiple importance weights of pt's two strategies and bdpt's (s,t) strategies, and so of the "
             "chain methods over them (mmlt's target is one strategy's weighted contribution): power (exponent 2) "
             "or balance")
      ->capture_default_str()
      ->check(CLI::IsMember({"power", "balance"}));
  maxDepthOpt_ = add_option("--max-depth", maxDepth_,
                            "Maximum path length in segments (edges): 1 = directly visible emitters "
                            "only, 2 = direct lighting, ...; -1 = unlimited (default: the scene's "
                            "<integrator> max_depth, else 5)")
                     ->check(CLI::Range(-1, 1 << 20));
  rrDepthOpt_ = add_option("--rr-depth", rrDepth_,
                           "Russian roulette starts after this many segments (default: the scene's "
                           "rr_depth, else 5)")
                    ->check(CLI::NonNegativeNumber);
  add_option("--seed", seed_, "Job seed (the image is a pure function of the settings and the seed)")
      ->capture_default_str();
  widthOpt_ = add_option("--width", width_, "Film width (default: the scene's)")->check(CLI::PositiveNumber);
  CLI::Option* height = add_option("--height", height_, "Film height (default: the scene's)")->check(CLI::PositiveNumber);
  widthOpt_->needs(height);
  height->needs(widthOpt_);
  add_option("-D,--define", defines_, "Scene parameter name=value (Mitsuba's -D), repeatable");
  // Every registered method's own parameters (RenderMethod::params), as --<name>. A name shared by two
  // methods is one option (registerMethod checks that its type is the same).
  for (const RenderMethod* m : allMethods()) {
    for (const ParamSpec& spec : m->params()) {
      auto it = params_.find(spec.name);
      if (it == params_.end()) {
        Param& p = params_[spec.name];
        p.option = add_option("--" + spec.name, p.value, "");
        it = params_.find(spec.name);
      }
      Param& p = it->second;
      p.methods.push_back(m->name());
      // Methods that share a parameter with the same help (the chain family's target) are named together.
      const std::string help = fmt::format("{} (default {})", spec.help, spec.defaultValue);
      auto same = std::find_if(p.helps.begin(), p.helps.end(), [&](const auto& h) { return h.second == help; });
      if (same == p.helps.end()) p.helps.emplace_back(m->name(), help);
      else same->first += ", " + m->name();
      std::string description;
      for (const auto& [names, text] : p.helps) description += (description.empty() ? "" : "; ") + names + ": " + text;
      p.option->description(description);
    }
  }
}

CommandLineSettings RenderSettingsOptions::settings() const {
  CommandLineSettings out;
  RenderSettings& s = out.settings;
  s.method = findMethod(method_).name();
  for (const auto& [name, p] : params_) {
    if (p.option->count() == 0) continue;
    if (std::find(p.methods.begin(), p.methods.end(), s.method) == p.methods.end())
      throw std::invalid_argument(fmt::format("--{} is a parameter of {}, not of --method {}", name,
                                              fmt::join(p.methods, ", "), s.method));
    s.params[name] = p.value;
  }
  findMethod(s.method).checkParams(s.params);  // names the parameter and the allowed values
  s.seed = seed_;
  s.width = width_;
  s.height = height_;
  out.hasSize = widthOpt_->count() > 0;  // --width and --height need each other
  s.spp = spp_;
  out.hasSpp = sppOpt_->count() > 0;
  s.samplesPerUnit = samplesPerUnit_;
  s.mutationsPerPixel = mutationsPerPixel_;
  s.chains = chains_;
  s.bootstrapSamples = bootstrap_;
  s.largeStepProb = largeStep_;
  s.kernel = kernel_ == "gaussian" ? MutationKernel::Gaussian : MutationKernel::Kelemen;
  if (s2_ < s1_)  // the kernel's steps lie in [s1, s2] (Kelemen et al. 2002, eq. 9)
    throw std::invalid_argument(fmt::format("--s2 ({}) must be at least --s1 ({})", s2_, s1_));
  s.kelemenS1 = s1_;
  s.kelemenS2 = s2_;
  s.gaussianSigma = sigma_;
  s.splatting = splattingFromName(splatting_).value();  // empty or one of the names --splatting accepts
  s.integrator.heuristic = misHeuristicFromName(heuristic_).value();  // a name --mis-heuristic accepts
  s.directLight = separateDirect_ ? DirectLight::Separate : directLightFromName(directLight_).value();  // a name --direct-light accepts
  // The direct pass without --spp: sized by the plan from the mutations per pixel and the pilot's share of the
  // light (directSppPerMutation, directSppFor), also under a time budget; the scene's sampler sample_count
  // is meant for pt and bdpt.
  if (separatesDirect(s) && !out.hasSpp) s.spp = 0;
  // Given depths go into the settings too; unset ones keep IntegratorSettings' defaults and are resolved
  // against the scene's <integrator> by whoever loads it (the in-process renderer or the coordinator).
  out.hasMaxDepth = maxDepthOpt_->count() > 0;
  if (out.hasMaxDepth) s.integrator.maxDepth = maxDepth_;
  out.hasRrDepth = rrDepthOpt_->count() > 0;
  if (out.hasRrDepth) s.integrator.rrDepth = rrDepth_;
  for (const std::string& d : defines_) {
    const size_t eq = d.find('=');
    if (eq == std::string::npos || eq == 0)
      throw std::invalid_argument("--define '" + d + "': expected name=value");
    out.defines[d.substr(0, eq)] = d.substr(eq + 1);
  }
  return out;
}

RenderSettingsOptions& addRenderSettingsOptions(CLI::App& app) {
  return *app.add_option_group<RenderSettingsOptions>(RenderSettingsOptions::kGroupName);
}

const RenderSettingsOptions* findRenderSettingsOptions(const CLI::App& app) {
  for (const CLI::App* group : app.get_subcommands([](const CLI::App* sub) { return sub->get_name().empty(); }))
    if (const auto* options = dynamic_cast<const RenderSettingsOptions*>(group)) return options;
  return nullptr;
}

wire::SubmittedSettings submittedSettings(const CommandLineSettings& s) {
  wire::SubmittedSettings w;
  w.settings = s.settings;
  w.hasSize = s.hasSize;
  w.hasSpp = s.hasSpp;
  w.hasMaxDepth = s.hasMaxDepth;
  w.hasRrDepth = s.hasRrDepth;
  w.defines = s.defines;
  return w;
}

}  // namespace mlt::cli
