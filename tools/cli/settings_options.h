// The render-setting options of the command line, declared once and shared by every command that starts
// a render (`mltfarm render`, `mltfarm submit`): same names, defaults, help and validation everywhere,
// so a setting the renderer knows cannot be missing from one of them.
//
// The options live in a CLI11 option group ("Render settings") that owns the parsed values; the group is
// a subcommand of the command's App, so it can be found again from the App alone (tests compare the
// groups of `render` and `submit` that way). Options specific to one command (render's -o/--time/
// --in-process, submit's --coordinator/--priority) are declared by that command, not here.
//
//   auto& settings = addRenderSettingsOptions(sub);       // while setting up the subcommand
//   CommandLineSettings s = settings.settings();          // after parsing; throws naming the option
#pragma once
#include <CLI/CLI.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/methods/registry.h"

namespace mlt::wire {
struct SubmittedSettings;  // proto/convert.h
}  // namespace mlt::wire

namespace mlt::cli {

// The settings as typed: RenderSettings with the built-in defaults where an option was not given, and
// which of the settings a scene file can also provide were given (those not given are taken from the
// scene: film size, <integrator> depths, sampler sample_count).
struct CommandLineSettings {
  RenderSettings settings;  // timeBudgetSeconds is render's own option (--time), never set here
  bool hasSpp = false, hasSize = false, hasMaxDepth = false, hasRrDepth = false;
  std::map<std::string, std::string> defines;  // -D name=value (Mitsuba's scene parameters)
};

class RenderSettingsOptions : public CLI::Option_group {
 public:
  static constexpr const char* kGroupName = "Render settings";

  // The signature CLI::App::add_option_group requires; registers every option on construction.
  RenderSettingsOptions(std::string description, std::string name, CLI::App* parent);

  // After parsing. Checks what a single option's validator cannot (--s2 against --s1, the form of
  // --define) and throws std::invalid_argument naming the option.
  CommandLineSettings settings() const;

 private:
  std::string method_ = "bdpt", kernel_ = "kelemen", splatting_, directLight_ = "auto", heuristic_ = "power";
  int spp_ = 16, samplesPerUnit_ = 0, width_ = 0, height_ = 0, maxDepth_ = 0, rrDepth_ = 0;
  int chains_ = 0, bootstrap_ = 0;
  double mutationsPerPixel_ = 16;
  float largeStep_ = -1.0f;  // the method's default
  float s1_ = 1.0f / 1024, s2_ = 1.0f / 64, sigma_ = 0.01f;
  bool separateDirect_ = false;
  uint64_t seed_ = 1;
  std::vector<std::string> defines_;
  struct Param {  // one method parameter's option (RenderMethod::params)
    std::string value;
    CLI::Option* option = nullptr;
    std::vector<std::string> methods;  // the methods that have it
    std::vector<std::pair<std::string, std::string>> helps;  // (methods, help): one entry per distinct help
  };
  std::map<std::string, Param> params_;
  CLI::Option *sppOpt_ = nullptr, *widthOpt_ = nullptr, *maxDepthOpt_ = nullptr, *rrDepthOpt_ = nullptr;
};

// Adds the group to a (sub)command; the returned object belongs to `app`.
RenderSettingsOptions& addRenderSettingsOptions(CLI::App& app);

// The group added to `app` by addRenderSettingsOptions; nullptr if it has none.
const RenderSettingsOptions* findRenderSettingsOptions(const CLI::App& app);

// The settings as `submit` sends them (proto/convert.h): every setting, which ones were given, the defines.
wire::SubmittedSettings submittedSettings(const CommandLineSettings& s);

}  // namespace mlt::cli
