// `mltfarm render` and `mltfarm submit` take their render settings from one shared option group
// (tools/cli/settings_options.h): both declare the same setting options (names, help, defaults), neither
// declares one a second time, the same arguments give the same settings (compared as they travel on the
// wire, so every field the farm carries counts), and a bad value is refused with the same error naming
// the option. The commands are set up from the real registry (the objects of the mltfarm executable),
// parsed but never run.
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/methods/registry.h"
#include "proto/convert.h"
#include "tools/cli/commands.h"
#include "tools/cli/settings_options.h"

namespace mlt::cli {
namespace {

// One subcommand set up as main.cpp does, under its own root App.
struct Command {
  CLI::App root{"test"};
  CLI::App* sub = nullptr;
  CommandRun run;  // never called, but kept: it owns the command's own option values
  explicit Command(const std::string& name) {
    for (const CommandInfo& c : commandRegistry())
      if (c.name == name) {
        sub = root.add_subcommand(c.name, c.description);
        run = c.setup(*sub);  // nothing renders or connects: `run` is never called
      }
    if (!sub) throw std::logic_error("no subcommand " + name);
  }
  // Parses `mltfarm NAME args...`; CLI11's exceptions propagate.
  const RenderSettingsOptions& parse(const std::vector<std::string>& args) {
    std::vector<std::string> argv{"mltfarm", sub->get_name()};
    argv.insert(argv.end(), args.begin(), args.end());
    std::vector<const char*> cargv;
    for (const std::string& a : argv) cargv.push_back(a.c_str());
    root.parse(int(cargv.size()), cargv.data());
    return group();
  }
  const RenderSettingsOptions& group() const {
    const RenderSettingsOptions* g = findRenderSettingsOptions(*sub);
    if (!g) throw std::logic_error(sub->get_name() + " has no render settings group");
    return *g;
  }
};

// The arguments each command needs besides the settings.
const std::vector<std::string> kRenderArgs{"scene.xml", "-o", "out.exr"};
const std::vector<std::string> kSubmitArgs{"scene.xml", "--coordinator", "127.0.0.1:1"};

CommandLineSettings parseRender(const std::vector<std::string>& settingsArgs) {
  Command c("render");
  std::vector<std::string> args = kRenderArgs;
  args.insert(args.end(), settingsArgs.begin(), settingsArgs.end());
  return c.parse(args).settings();
}
CommandLineSettings parseSubmit(const std::vector<std::string>& settingsArgs) {
  Command c("submit");
  std::vector<std::string> args = kSubmitArgs;
  args.insert(args.end(), settingsArgs.begin(), settingsArgs.end());
  return c.parse(args).settings();
}

// Settings as the farm receives them: every wire field, the "given" flags and the defines.
v1::RenderSettings onTheWire(const CommandLineSettings& s) { return wire::toProto(submittedSettings(s)); }

void expectSame(const CommandLineSettings& a, const CommandLineSettings& b) {
  std::string diff;
  google::protobuf::util::MessageDifferencer d;
  d.ReportDifferencesToString(&diff);
  EXPECT_TRUE(d.Compare(onTheWire(a), onTheWire(b))) << diff;
  EXPECT_EQ(a.settings.timeBudgetSeconds, b.settings.timeBudgetSeconds);  // not on the wire
}

// "--spp", "-m,--method", ...: every name of every option, with its help and default.
struct OptionShape {
  std::string names, description, defaultValue;
  bool operator<(const OptionShape& o) const { return names < o.names; }
  bool operator==(const OptionShape& o) const = default;
};
std::set<OptionShape> shapes(const CLI::App& app) {
  std::set<OptionShape> out;
  for (const CLI::Option* opt : app.get_options())
    if (opt->get_name() != "--help")
      out.insert({opt->get_name(false, true), opt->get_description(), opt->get_default_str()});
  return out;
}

TEST(CliSettings, RenderAndSubmitDeclareTheSameSettingOptionsOnce) {
  const Command render("render"), submit("submit");
  const std::set<OptionShape> r = shapes(render.group()), s = shapes(submit.group());
  EXPECT_TRUE(r == s);
  // Every setting the wire carries has its option (the ones submit used to lack included).
  std::set<std::string> names;
  for (const OptionShape& o : r) names.insert(o.names);
  for (const char* expected :
       {"-m,--method", "--spp", "--samples-per-unit", "--mutations-per-pixel", "--chains", "--bootstrap",
        "--large-step", "--kernel", "--s1", "--s2", "--sigma", "--splatting", "--direct-light", "--separate-direct", "--mis-heuristic", "--max-depth",
        "--rr-depth", "--seed", "--width", "--height", "-D,--define"})
    EXPECT_TRUE(names.count(expected)) << expected << " is not a shared setting option";
  // ... and one option per registered method parameter (--<name>, e.g. veach-mlt's --veach-lens).
  std::set<std::string> params;
  for (const RenderMethod* m : allMethods())
    for (const ParamSpec& p : m->params()) {
      params.insert(p.name);
      EXPECT_TRUE(names.count("--" + p.name)) << "--" << p.name << " is not a shared setting option";
    }
  EXPECT_EQ(names.size(), 21u + params.size());
  // Nothing declared twice: no option of the command itself has a name of a setting option.
  for (const Command* c : {&render, &submit})
    for (const CLI::Option* opt : c->sub->get_options()) {
      if (opt == c->sub->get_help_ptr()) continue;  // every App (the group too) has --help
      for (const std::string& n : opt->get_lnames())
        EXPECT_EQ(c->group().get_option_no_throw("--" + n), nullptr)
            << c->sub->get_name() << " declares --" << n << " besides the shared group";
    }
}

TEST(CliSettings, SameArgumentsGiveTheSameSettings) {
  const std::vector<std::string> args{
      "-m", "mmlt", "--kernel", "gaussian", "--sigma", "0.02", "--splatting", "kelemen-mis", "--separate-direct",
      "--seed", "9", "--width", "40", "--height", "30", "--max-depth", "6", "--rr-depth", "3", "--spp", "4",
      "--samples-per-unit", "2", "--mutations-per-pixel", "3.5", "--chains", "12", "--bootstrap", "5000",
      "--large-step", "0.25", "--s1", "0.002", "--s2", "0.03", "--mis-heuristic", "balance", "-D", "a=1",
      "--define", "b=x=y"};
  const CommandLineSettings r = parseRender(args), s = parseSubmit(args);
  expectSame(r, s);
  // And they are the values typed (a parser that dropped an option would still agree with itself).
  const RenderSettings& v = s.settings;
  EXPECT_EQ(v.method, "mmlt");
  EXPECT_EQ(v.kernel, MutationKernel::Gaussian);
  EXPECT_EQ(v.gaussianSigma, 0.02f);
  EXPECT_EQ(v.splatting, MltSplatting::KelemenMIS);
  EXPECT_EQ(v.directLight, DirectLight::Separate);
  EXPECT_EQ(v.seed, 9u);
  EXPECT_EQ(v.width, 40);
  EXPECT_EQ(v.height, 30);
  EXPECT_EQ(v.integrator.maxDepth, 6);
  EXPECT_EQ(v.integrator.rrDepth, 3);
  EXPECT_EQ(v.integrator.heuristic, MisHeuristic::Balance);
  EXPECT_EQ(v.spp, 4);
  EXPECT_EQ(v.samplesPerUnit, 2);
  EXPECT_EQ(v.mutationsPerPixel, 3.5);
  EXPECT_EQ(v.chains, 12);
  EXPECT_EQ(v.bootstrapSamples, 5000);
  EXPECT_EQ(v.largeStepProb, 0.25f);
  EXPECT_EQ(v.kelemenS1, 0.002f);
  EXPECT_EQ(v.kelemenS2, 0.03f);
  EXPECT_TRUE(s.hasSize && s.hasSpp && s.hasMaxDepth && s.hasRrDepth);
  EXPECT_EQ(s.defines, (std::map<std::string, std::string>{{"a", "1"}, {"b", "x=y"}}));
}

TEST(CliSettings, WithoutOptionsTheSettingsAreTheDefaultsAndNothingIsGiven) {
  const CommandLineSettings r = parseRender({}), s = parseSubmit({});
  expectSame(r, s);
  CommandLineSettings defaults;  // RenderSettings' own defaults: the scene fills in what is not given
  expectSame(s, defaults);
  EXPECT_FALSE(s.hasSize || s.hasSpp || s.hasMaxDepth || s.hasRrDepth);
  // A value equal to the default still counts as given (it overrides the scene's).
  const CommandLineSettings given = parseSubmit({"--spp", "16", "--max-depth", "5"});
  EXPECT_TRUE(given.hasSpp && given.hasMaxDepth);
  EXPECT_FALSE(given.hasRrDepth);
}

// --separate-direct without --spp leaves the direct pass to the plan (spp 0, directSppFor), in render and
// submit alike; with --spp it is the value typed.
TEST(CliSettings, SeparateDirectWithoutSppLeavesTheDirectPassToThePlan) {
  const std::vector<std::string> args{"-m", "mmlt", "--separate-direct", "--mutations-per-pixel", "20"};
  const CommandLineSettings r = parseRender(args), s = parseSubmit(args);
  expectSame(r, s);
  EXPECT_EQ(s.settings.spp, 0);
  EXPECT_FALSE(s.hasSpp);
  EXPECT_EQ(wire::fromProto(onTheWire(s)).settings.spp, 0);  // the wire carries "sized by the plan"
  std::vector<std::string> withSpp = args;
  withSpp.insert(withSpp.end(), {"--spp", "7"});
  EXPECT_EQ(parseSubmit(withSpp).settings.spp, 7);
  EXPECT_EQ(parseSubmit({"-m", "mmlt"}).settings.spp, RenderSettings{}.spp);  // no direct pass: untouched
}

// The error of `mltfarm CMD args`: CLI11's parse error or the group's own check, whichever comes first.
std::string errorOf(const std::string& command, const std::vector<std::string>& settingsArgs) {
  Command c(command);
  std::vector<std::string> args = command == "render" ? kRenderArgs : kSubmitArgs;
  args.insert(args.end(), settingsArgs.begin(), settingsArgs.end());
  try {
    c.parse(args).settings();
  } catch (const CLI::ParseError& e) {
    return e.what();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// --direct-light: auto by default (the plan's pilot decides), chains or separate as typed, and the wire
// carries each by name; --separate-direct is --direct-light separate, and the two together are refused.
// A writer from before direct_light (only separate_direct) still reads as it meant: separate, or no
// choice made (now auto); an unknown name is a WireError naming the field.
TEST(CliSettings, DirectLightIsAutoUnlessGivenAndTravelsByName) {
  EXPECT_EQ(parseSubmit({"-m", "mmlt"}).settings.directLight, DirectLight::Auto);
  for (const auto& [name, value] : {std::pair<const char*, DirectLight>{"auto", DirectLight::Auto},
                                    {"chains", DirectLight::Chains},
                                    {"separate", DirectLight::Separate},
                                    {"emission", DirectLight::Emission}}) {
    const std::vector<std::string> args{"-m", "mmlt", "--direct-light", name};
    const CommandLineSettings r = parseRender(args), s = parseSubmit(args);
    expectSame(r, s);
    EXPECT_EQ(s.settings.directLight, value) << name;
    EXPECT_EQ(s.settings.spp, separatesDirect(s.settings) ? 0 : RenderSettings{}.spp) << name;
    const v1::RenderSettings wire = onTheWire(s);
    EXPECT_EQ(wire.chains().direct_light(), name);
    EXPECT_EQ(wire.chains().separate_direct(), value == DirectLight::Separate);  // for readers before direct_light
    EXPECT_EQ(wire::fromProto(wire).settings.directLight, value) << name;
  }
  expectSame(parseSubmit({"-m", "mmlt", "--separate-direct"}), parseSubmit({"-m", "mmlt", "--direct-light", "separate"}));
  EXPECT_NE(errorOf("submit", {"-m", "mmlt", "--separate-direct", "--direct-light", "chains"}), "");
  EXPECT_NE(errorOf("submit", {"--direct-light", "bdpt"}).find("--direct-light"), std::string::npos);

  v1::RenderSettings old = onTheWire(parseSubmit({"-m", "mmlt"}));
  old.mutable_chains()->clear_direct_light();
  old.mutable_chains()->set_separate_direct(true);
  old.mutable_chains()->mutable_direct()->set_spp(0);  // what such a writer sent for --separate-direct
  EXPECT_EQ(wire::fromProto(old).settings.directLight, DirectLight::Separate);
  EXPECT_EQ(wire::fromProto(old).settings.spp, 0);  // sized by the plan, as it was
  old.mutable_chains()->set_separate_direct(false);
  EXPECT_EQ(wire::fromProto(old).settings.directLight, DirectLight::Auto);
  old.mutable_chains()->set_direct_light("sometimes");
  try {
    wire::fromProto(old);
    ADD_FAILURE() << "an unknown direct_light was accepted";
  } catch (const wire::WireError& e) {
    EXPECT_NE(std::string(e.what()).find("settings.chains.direct_light"), std::string::npos) << e.what();
  }
}

// --mis-heuristic: power unless given (the renderer's default, IntegratorSettings), balance as typed; the
// wire carries it by name and reads it back.
TEST(CliSettings, MisHeuristicIsPowerUnlessGivenAndTravelsByName) {
  EXPECT_EQ(parseSubmit({"-m", "bdpt"}).settings.integrator.heuristic, MisHeuristic::Power);
  EXPECT_EQ(RenderSettings{}.integrator.heuristic, MisHeuristic::Power);
  for (const auto& [name, value] : {std::pair<const char*, MisHeuristic>{"power", MisHeuristic::Power},
                                    {"balance", MisHeuristic::Balance}}) {
    const std::vector<std::string> args{"-m", "mmlt", "--mis-heuristic", name};
    const CommandLineSettings r = parseRender(args), s = parseSubmit(args);
    expectSame(r, s);
    EXPECT_EQ(s.settings.integrator.heuristic, value) << name;
    const v1::RenderSettings wire = onTheWire(s);
    EXPECT_EQ(wire.mis_heuristic(), name);
    EXPECT_EQ(wire::fromProto(wire).settings.integrator.heuristic, value) << name;
  }
}

TEST(CliSettings, BadValuesAreErrorsNamingTheOption) {
  struct Case {
    std::vector<std::string> args;
    std::string option;
  };
  for (const Case& k : std::vector<Case>{{{"--kernel", "nonsense"}, "--kernel"},
                                          {{"--splatting", "veach"}, "--splatting"},
                                          {{"--mis-heuristic", "max"}, "--mis-heuristic"},
                                          {{"--sigma", "0"}, "--sigma"},
                                          {{"--sigma", "1.5"}, "--sigma"},
                                          {{"--s1", "-0.1"}, "--s1"},
                                          {{"--s1", "0.1", "--s2", "0.05"}, "--s2"},
                                          {{"--large-step", "2"}, "--large-step"},
                                          {{"--method", "vcm"}, "--method"},
                                          {{"--spp", "0"}, "--spp"},
                                          {{"--max-depth", "-2"}, "--max-depth"},
                                          {{"--width", "32"}, "--height"},
                                          {{"-D", "novalue"}, "--define"}}) {
    const std::string r = errorOf("render", k.args), s = errorOf("submit", k.args);
    EXPECT_NE(s.find(k.option), std::string::npos) << k.args[0] << " " << k.args[1] << ": '" << s << "'";
    EXPECT_EQ(r, s) << "render and submit disagree on " << k.args[0] << " " << k.args[1];
  }
  // The bounds are inclusive where the wire's are: sigma = 1 and s1 = s2 are settings, not errors.
  EXPECT_EQ(errorOf("submit", {"--sigma", "1", "--s1", "0.01", "--s2", "0.01"}), "");
}

}  // namespace
}  // namespace mlt::cli
