// Reversible-jump MLT's chain state (see rjmlt_chain.h).
#include "common/methods/rjmlt/rjmlt_chain.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "common/methods/mmlt/mmlt_method.h"
#include "common/render/render_scene.h"

namespace mlt {

RjmltState::RjmltState(const RenderScene& scene, KelemenSource& source, int pathLength, MisHeuristic heuristic,
                       const RjmltSettings& settings, Pcg32 moves)
    : scene_(scene), source_(source), k_(pathLength), n_(mmltTechniqueCount(pathLength)), heuristic_(heuristic),
      settings_(settings), moves_(moves) {
  if (k_ < 1) throw std::invalid_argument("rjmlt: path length " + std::to_string(k_) + " must be >= 1");
  if (!(settings.largeStepProb >= 0 && settings.techniqueProb >= 0 &&
        settings.largeStepProb + settings.techniqueProb <= 1))
    throw std::invalid_argument("rjmlt: large-step and technique probabilities must be >= 0 and sum to <= 1");
  ws_.reserve(k_ + 2, k_ + 1);
}

void RjmltState::trace(int s, PathContribution& out) {
  out.clear();
  proposedValid_ = traceTechnique(scene_, source_, s, k_ + 1 - s, heuristic_, ws_, &proposed_);
  if (proposedValid_) appendMmltSplat(proposed_, out);
}

double RjmltState::start(PathContribution& out) {
  sProposed_ = mmltTechniqueOf(source_, k_);
  kind_ = kRjmltSmall;
  jumpFailed_ = false;
  trace(sProposed_, out);
  accept();
  double c = 0;
  for (const Splat& sp : out.splats) c += luminance(sp.L);
  return c;
}

void RjmltState::adopt(const MmltPath& start, bool valid) {
  s_ = start.s;
  current_ = start;
  currentValid_ = valid;
}

Proposal RjmltState::propose() {
  const double r = moves_.uniformDouble();
  jumpFailed_ = false;
  if (r < settings_.largeStepProb) {
    kind_ = kRjmltLarge;
    source_.startIteration(MutationType::Large);
    sProposed_ = mmltTechniqueOf(source_, k_);  // a fresh uniform, as MMLT's large step draws it
    return {kRjmltLarge, 1.0, true};
  }
  if (r < settings_.largeStepProb + settings_.techniqueProb && n_ > 1) {
    kind_ = kRjmltTechnique;
    source_.startIteration(MutationType::Small);  // no coordinate is mutated: the jump writes all it reads
    std::optional<PathInverse> inv, cur;
    double tForward = 1, tBackward = 1;  // T(i->j), T(j->i)
    int j = s_;
    if (currentValid_ && settings_.proposal == TechniqueProposal::Uniform) {
      j = (s_ + 1 + std::min(n_ - 2, static_cast<int>(moves_.uniform() * float(n_ - 1)))) % n_;
      inv = invertTechnique(scene_, current_.z, j, k_ + 1 - j, moves_);
      cur = invertTechnique(scene_, current_.z, s_, k_ + 1 - s_, moves_);
    } else if (currentValid_) {
      // T(i->j) = w~_j(z) = J_j^2 / sum_m J_m^2 over the techniques that can produce z (power heuristic).
      invs_.assign(n_, std::nullopt);
      weights_.assign(n_, 0.0);
      double maxJ = 0;
      for (int m = 0; m < n_; ++m) {
        if (connectsAtDelta(current_.z, m, k_ + 1 - m) && m != s_) continue;
        invs_[m] = invertTechnique(scene_, current_.z, m, k_ + 1 - m, moves_);
        if (invs_[m]) maxJ = std::max(maxJ, invs_[m]->jacobian);
      }
      double sum = 0;
      for (int m = 0; m < n_; ++m)
        if (invs_[m] && maxJ > 0 && !connectsAtDelta(current_.z, m, k_ + 1 - m)) {
          const double ratio = invs_[m]->jacobian / maxJ;
          weights_[m] = ratio * ratio;
          sum += weights_[m];
        }
      if (sum > 0 && weights_[s_] > 0) {
        double u = moves_.uniformDouble() * sum;
        j = -1;
        for (int m = 0; m < n_; ++m) {
          if (!(weights_[m] > 0)) continue;
          j = m;
          if (u < weights_[m]) break;
          u -= weights_[m];
        }
        tForward = weights_[j] / sum;
        tBackward = weights_[s_] / sum;
        inv = std::move(invs_[j]);
        cur = j == s_ ? inv : std::move(invs_[s_]);
      }
    }
    sProposed_ = j;
    if (j != s_) ++changesProposed_;
    if (!inv || !cur) {
      jumpFailed_ = true;
      ++inversionFailures_;
      return {kRjmltTechnique, 0.0, false};
    }
    for (const PrimaryWrite& w : inv->writes) source_.write(w.stream, w.index, w.value);
    // Eq. 38: tRatio = T(j->i) |J[S_j^-1](z)| / (T(i->j) |J[S_i^-1](z)|).
    const double jacobianRatio = settings_.dropJacobian ? 1.0 : inv->jacobian / cur->jacobian;
    return {kRjmltTechnique, tBackward / tForward * jacobianRatio, false};
  }
  kind_ = kRjmltSmall;
  source_.startIteration(MutationType::Small);
  sProposed_ = s_;
  return {kRjmltSmall, 1.0, false};
}

void RjmltState::evaluate(PathContribution& out) {
  out.clear();
  if (jumpFailed_) {
    proposedValid_ = false;
    return;
  }
  trace(sProposed_, out);
  if (kind_ == kRjmltTechnique && !out.splats.empty() && !samePath(scene_, current_.z, proposed_.z)) {
    out.clear();  // the numbers did not reproduce the path: reject (never abort)
    ++retraceFailures_;
  }
}

void RjmltState::accept() {
  if (kind_ == kRjmltTechnique && sProposed_ != s_) ++changesAccepted_;
  source_.accept();
  s_ = sProposed_;
  std::swap(current_, proposed_);
  currentValid_ = proposedValid_;
}

void RjmltState::reject() { source_.reject(); }

}  // namespace mlt
