// Primary-sample-space pieces for the chain loop (chain.h): the state is a KelemenSource, the target runs
// a PathEvaluator on it, the sink splats into a Film.
#pragma once
#include <functional>

#include "common/film/film.h"
#include "common/integrators/path_evaluator.h"
#include "common/mlt/chain.h"
#include "common/mlt/kelemen_source.h"

namespace mlt {

class PssState final : public ChainState {
 public:
  explicit PssState(KelemenSource& source) : source_(source) {}
  Proposal propose() override { return {source_.startIteration(), 1.0}; }  // symmetric kernels: T-ratio 1
  void accept() override { source_.accept(); }
  void reject() override { source_.reject(); }

 private:
  KelemenSource& source_;
};

// Evaluates a path evaluator on a sample source (the film position comes from the camera stream).
// An optional filter drops splats before the target value is computed (separateDirect: the chains carry
// only the paths the direct pass does not).
class EvaluatorTarget final : public ChainTarget {
 public:
  using SplatFilter = bool (*)(const Splat&);
  EvaluatorTarget(const PathEvaluator& evaluator, SampleSource& source, SplatFilter keep = nullptr)
      : evaluator_(evaluator), source_(source), keep_(keep) {}
  void evaluate(PathContribution& out) override {
    evaluator_.evaluate(source_, nullptr, out);
    if (keep_) std::erase_if(out.splats, [this](const Splat& s) { return !keep_(s); });
  }

 private:
  const PathEvaluator& evaluator_;
  SampleSource& source_;
  SplatFilter keep_;
};

// Splats into a film's splat buffer; `scale` multiplies every weight (mmlt's r_k, develop.h (D2)).
class FilmSink final : public ChainSink {
 public:
  explicit FilmSink(Film& film, double scale = 1.0) : film_(film), scale_(scale) {}
  void splat(const PathContribution& path, double weight) override {
    const float w = static_cast<float>(weight * scale_);
    for (const Splat& s : path.splats) film_.addSplat(s.pRaster, s.L * w);
  }

 private:
  Film& film_;
  double scale_;
};

}  // namespace mlt
