// The defaults of RenderMethod: common checks and the method's own parameters.
#include "common/methods/method.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "common/mlt/develop.h"

namespace mlt {

namespace {

const ParamSpec* findSpec(const std::vector<ParamSpec>& specs, const std::string& name) {
  for (const ParamSpec& p : specs)
    if (p.name == name) return &p;
  return nullptr;
}

// The value of `text` for `spec`, or std::invalid_argument naming the parameter.
double parseParam(const std::string& method, const ParamSpec& spec, const std::string& text) {
  auto bad = [&](const std::string& why) {
    return std::invalid_argument(fmt::format("settings: {} parameter '{}' = '{}': {}", method, spec.name, text, why));
  };
  switch (spec.type) {
    case ParamSpec::Type::Bool:
      if (text == "true" || text == "1") return 1;
      if (text == "false" || text == "0") return 0;
      throw bad("expected true or false");
    case ParamSpec::Type::Choice:
      for (size_t i = 0; i < spec.choices.size(); ++i)
        if (spec.choices[i] == text) return double(i);
      throw bad(fmt::format("expected one of {}", fmt::join(spec.choices, ", ")));
    case ParamSpec::Type::Int:
    case ParamSpec::Type::Double: {
      size_t used = 0;
      double v = 0;
      try {
        v = std::stod(text, &used);
      } catch (const std::exception&) {
        throw bad("not a number");
      }
      if (used != text.size() || !std::isfinite(v)) throw bad("not a finite number");
      if (spec.type == ParamSpec::Type::Int && v != std::floor(v)) throw bad("expected an integer");
      if (v < spec.min || (spec.max >= spec.min && v > spec.max))
        throw bad(spec.max >= spec.min ? fmt::format("must be in [{}, {}]", spec.min, spec.max)
                                       : fmt::format("must be >= {}", spec.min));
      return v;
    }
  }
  throw bad("unknown parameter type");
}

}  // namespace

void RenderMethod::validate(const RenderSettings& s) const {
  if (s.method != name())
    throw std::invalid_argument(fmt::format("settings: method is '{}', not '{}'", s.method, name()));
  if (s.width < 0 || s.height < 0) throw std::invalid_argument("settings: film size must be >= 0 (0 = the scene's)");
  if (s.integrator.maxDepth < -1) throw std::invalid_argument("settings: max depth must be >= -1 (-1 = unlimited)");
  if (s.integrator.rrDepth < 0) throw std::invalid_argument("settings: rr depth must be >= 0");
  checkParams(s.params);
}

void RenderMethod::checkParams(const MethodParams& given) const {
  const std::vector<ParamSpec> specs = params();
  for (const auto& [key, value] : given) {
    const ParamSpec* spec = findSpec(specs, key);
    if (!spec) {
      std::vector<std::string> names;
      for (const ParamSpec& p : specs) names.push_back(p.name);
      throw std::invalid_argument(fmt::format("settings: method {} has no parameter '{}'{}", name(), key,
                                              names.empty() ? std::string(" (it has none)")
                                                            : fmt::format(" (it has: {})", fmt::join(names, ", "))));
    }
    parseParam(name(), *spec, value);
  }
  for (const ParamSpec& spec : specs) parseParam(name(), spec, spec.defaultValue);  // a method's own bug
}

uint64_t RenderMethod::unitWork(const JobPlan& plan, const WorkUnit& unit) const {
  if (family() == MethodFamily::MarkovChain) return unit.mutations;
  return uint64_t(unit.sampleEnd - unit.sampleBegin) * uint64_t(plan.settings.width) * uint64_t(plan.settings.height);
}

size_t RenderMethod::filmLayers(const JobPlan& plan) const {
  return family() == MethodFamily::MarkovChain
             ? chainFilmLayers(plan.norm.mutationsPerLength, plan.settings.splatting == MltSplatting::KelemenMIS)
             : 1;
}

std::string RenderMethod::paramText(const RenderSettings& s, const std::string& key) const {
  const std::vector<ParamSpec> specs = params();
  const ParamSpec* spec = findSpec(specs, key);
  if (!spec) throw std::invalid_argument(fmt::format("method {} has no parameter '{}'", name(), key));
  const auto it = s.params.find(key);
  return it == s.params.end() ? spec->defaultValue : it->second;
}

double RenderMethod::param(const RenderSettings& s, const std::string& key) const {
  const std::vector<ParamSpec> specs = params();
  const ParamSpec* spec = findSpec(specs, key);
  if (!spec) throw std::invalid_argument(fmt::format("method {} has no parameter '{}'", name(), key));
  const auto it = s.params.find(key);
  return parseParam(name(), *spec, it == s.params.end() ? spec->defaultValue : it->second);
}

}  // namespace mlt
