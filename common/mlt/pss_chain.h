// Primary-sample-space pieces for the chain loop (chain.h): the state is a KelemenSource, the target runs
// a PathEvaluator on it, the sink splats into a Film.
#pragma once
#include <stdexcept>
#include <string>

#include "common/film/film.h"
#include "common/film/sparse_splats.h"
#include "common/integrators/path_evaluator.h"
#include "common/mlt/chain.h"
#include "common/mlt/kelemen_source.h"
#include "common/mlt/strata.h"

namespace mlt {

class PssState final : public ChainState {
 public:
  explicit PssState(KelemenSource& source) : source_(source) {}
  Proposal propose() override {  // symmetric kernels: T-ratio 1
    const MutationType t = source_.startIteration();
    return {int(t), 1.0, t == MutationType::Large};
  }
  Vec2 stratumPoint() override { return source_.filmPositionNumbers(); }
  void accept() override { source_.accept(); }
  void reject() override { source_.reject(); }

 private:
  KelemenSource& source_;
};

// The function a primary-sample chain method samples, as a map (sample source, path length) -> path
// contribution. The bootstrap and the chains call the same object, so a chain's replay of its start
// candidate reproduces the bootstrap's value bit for bit. Each method supplies its own (pssmlt: the path
// tracer; pssmlt-bdpt: bdpt; mmlt: one technique per length, common/methods/<name>/).
class PssTarget {
 public:
  virtual ~PssTarget() = default;
  // pathLength: the chain's path length k for methods with chains per length; -1 otherwise.
  virtual void evaluate(SampleSource& source, int pathLength, PathContribution& out) = 0;
  // A Rao-Blackwellized b sample (develop.h (D9)): on a uniform `source`, the mean of c over the coordinates
  // that only choose among the path's techniques, given the others, so E = b_k with a variance no larger
  // than c's; >= 0 and finite (non-finite counts as 0, as targetFunction). Called only for the lengths where
  // the method's ChainJobSpec::mutationsPerBSample is > 0 (mmlt, rjmlt: one technique of several).
  virtual double bSample(SampleSource& source, int pathLength) {
    (void)source;
    throw std::logic_error("this target has no b sample of its own for path length " + std::to_string(pathLength));
  }
};

// ChainTarget adapter: evaluates a PssTarget on a fixed source and length.
class PssChainTarget final : public ChainTarget {
 public:
  PssChainTarget(PssTarget& target, SampleSource& source, int pathLength)
      : target_(target), source_(source), pathLength_(pathLength) {}
  void evaluate(PathContribution& out) override { target_.evaluate(source_, pathLength_, out); }

 private:
  PssTarget& target_;
  SampleSource& source_;
  int pathLength_;
};

// Evaluates a path evaluator on a sample source (the film position comes from the camera stream): the
// minimal ChainTarget for custom evaluators (tests, benchmarks).
class EvaluatorTarget final : public ChainTarget {
 public:
  EvaluatorTarget(const PathEvaluator& evaluator, SampleSource& source) : evaluator_(evaluator), source_(source) {}
  void evaluate(PathContribution& out) override { evaluator_.evaluate(source_, nullptr, out); }

 private:
  const PathEvaluator& evaluator_;
  SampleSource& source_;
};

// Splats into one splat layer of a film (a Markov chain job: chainLayer(path length slot), develop.h (D2)),
// unscaled: normalization happens only when the film is developed.
// largeStepLayer (Kelemen MIS, chain.h (K1)): the layer of the large steps' own share; by default `layer`.
class FilmSink final : public ChainSink {
 public:
  explicit FilmSink(Film& film, size_t layer = 0) : FilmSink(film, layer, layer) {}
  FilmSink(Film& film, size_t layer, size_t largeStepLayer)
      : film_(film), layer_(layer), largeStepLayer_(largeStepLayer) {}
  FilmSink(Film&, double) = delete;  // the sink takes a layer, not a weight scale (scales apply at develop)
  void splat(const PathContribution& path, double weight) override { add(path, weight, layer_); }
  void largeStepSplat(const PathContribution& path, double weight) override { add(path, weight, largeStepLayer_); }

 private:
  void add(const PathContribution& path, double weight, size_t layer) {
    const float w = static_cast<float>(weight);
    for (const Splat& s : path.splats) film_.addSplat(s.pRaster, s.L * w, layer);
  }
  Film& film_;
  size_t layer_, largeStepLayer_;
};

// Splats into one unit's sparse splat buffer (common/film/sparse_splats.h), unscaled like FilmSink: what
// a chain work unit uses, so that it never allocates or scans a dense film.
// strata (optional): the unit's b strata layer (develop.h (D6)), on a film of the same size.
// largeSteps (optional): Kelemen MIS's large-step layer (chain.h (K1)); without it they go to `splatter`.
class SparseSink final : public ChainSink {
 public:
  explicit SparseSink(SparseSplatter& splatter, SparseSplatter* strata = nullptr, SparseSplatter* largeSteps = nullptr)
      : splatter_(splatter), strata_(strata), largeSteps_(largeSteps ? *largeSteps : splatter) {}
  void splat(const PathContribution& path, double weight) override { add(splatter_, path, weight); }
  void largeStepSplat(const PathContribution& path, double weight) override { add(largeSteps_, path, weight); }
  void stratumSample(Vec2 u, double m) override {
    if (strata_) strata_->addAt(strataPixel(u.x, u.y, strata_->width(), strata_->height()), strataSample(m));
  }

 private:
  static void add(SparseSplatter& to, const PathContribution& path, double weight) {
    const float w = static_cast<float>(weight);
    for (const Splat& s : path.splats) to.addSplat(s.pRaster, s.L * w);
  }
  SparseSplatter& splatter_;
  SparseSplatter* strata_;
  SparseSplatter& largeSteps_;
};

}  // namespace mlt
