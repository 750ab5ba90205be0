#include "common/mlt/kelemen_source.h"

#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mlt {

Pcg32 chainRng(uint64_t jobSeed, uint64_t chainIndex, uint64_t purpose) {
  return Pcg32(hashKeys(jobSeed, chainIndex, purpose, 0x6d6c74636861696eULL), hashKeys(purpose, jobSeed, chainIndex));
}

namespace {

// Smallest n with max_f |E[exp(2 pi i f dv)]|^n < 2^-30 for the exponential kernel's offset dv (random
// sign, log-uniform magnitude in [s1, s2]). The density of the sum of n offsets mod 1 deviates from
// uniform by at most 2 sum_f |phi_f|^n; beyond this n, drawing a uniform is exact to float precision and
// saves applying thousands of pending steps to a coordinate that was unread for a long time.
int64_t computeExponentialUniformAfter(float s1, float s2) {
  const double l0 = std::log(double(s1)), l1 = std::log(double(s2));
  double worst = 0;
  for (int f = 1; f <= 16; ++f) {
    const int n = 4096;
    double sum = 0;
    for (int i = 0; i < n; ++i) sum += std::cos(2 * M_PI * f * std::exp(l0 + (l1 - l0) * (i + 0.5) / n));
    worst = std::fmax(worst, std::fabs(sum / n));
  }
  if (worst >= 1) return INT64_MAX;
  return static_cast<int64_t>(std::ceil(-30 * std::log(2.0) / std::log(worst)));
}

// Cached per thread (a chain constructs one source; computing this costs ~65k transcendentals).
int64_t exponentialUniformAfter(float s1, float s2) {
  thread_local float lastS1 = -1, lastS2 = -1;
  thread_local int64_t last = 0;
  if (s1 != lastS1 || s2 != lastS2) {
    last = computeExponentialUniformAfter(s1, s2);
    lastS1 = s1;
    lastS2 = s2;
  }
  return last;
}

inline float wrap01(double v) {
  v -= std::floor(v);
  const float f = static_cast<float>(v);
  return f >= 1.0f ? 0.0f : f;
}

}  // namespace

KelemenSource::KelemenSource(const KelemenParams& params, uint64_t jobSeed, uint64_t chainIndex,
                             uint64_t startCandidate)
    : params_(params), jobSeed_(jobSeed), chainIndex_(chainIndex),
      candidate_(IndependentSource::candidate(jobSeed, startCandidate)), rng_(chainRng(jobSeed, chainIndex, 0)) {
  if (!(params.largeStepProb >= 0 && params.largeStepProb <= 1))
    throw std::invalid_argument("KelemenSource: largeStepProb " + std::to_string(params.largeStepProb) +
                                " is outside [0, 1]");
  if (params.kernel == SmallStepKernel::Kelemen && !(params.s1 > 0 && params.s2 >= params.s1 && params.s2 < 1))
    throw std::invalid_argument("KelemenSource: need 0 < s1 <= s2 < 1 (s1 = " + std::to_string(params.s1) +
                                ", s2 = " + std::to_string(params.s2) + ")");
  if (params.kernel == SmallStepKernel::Gaussian && !(params.sigma > 0))
    throw std::invalid_argument("KelemenSource: Gaussian sigma must be > 0 (got " + std::to_string(params.sigma) + ")");
  logRatio_ = std::log(params.s2 / params.s1);
  for (int i = 0; i <= kStepTable; ++i)
    stepTable_[i] = float(double(params.s2) * std::exp(-double(logRatio_) * i / kStepTable));
  for (int i = 0; i < kStepTable; ++i) stepDiff_[i] = stepTable_[i + 1] - stepTable_[i];
  uniformAfter_ = params.kernel == SmallStepKernel::Kelemen ? exponentialUniformAfter(params.s1, params.s2) : 0;
  singleStepInline_ = params.kernel == SmallStepKernel::Kelemen && uniformAfter_ > 1;
  for (auto& v : coords_) v.reserve(128);
  touched_.resize(256);
}

MutationType KelemenSource::startIteration() {
  const MutationType t = rng_.uniform() < params_.largeStepProb ? MutationType::Large : MutationType::Small;
  startIteration(t);
  return t;
}

void KelemenSource::startIteration(MutationType type) {
  ++iteration_;
  largeStep_ = type == MutationType::Large;
  nTouched_ = 0;
}

void KelemenSource::accept() {
  if (largeStep_) lastLargeStep_ = iteration_;
  nTouched_ = 0;
}

void KelemenSource::reject() {
  if (iteration_ == 0) throw std::logic_error("KelemenSource::reject: the start state (iteration 0) cannot be rejected");
  for (size_t i = 0; i < nTouched_; ++i) {
    const Touched& t = touched_[i];
    Coord& c = coords_[t.stream][t.index];
    c.value = c.backupValue;
    c.modify = c.backupModify;
  }
  nTouched_ = 0;
  --iteration_;
}

// The hot path of every chain (~45 reads per pssmlt mutation): one function with the common cases
// inlined (coordinate already current; one pending small step), shared by next1D() and read().
[[gnu::always_inline]] inline float KelemenSource::readImpl(int stream, int index) {
  std::vector<Coord>& v = coords_[stream];
  Coord& c = static_cast<size_t>(index) < v.size() ? v[index] : grow(stream, index);
  if (c.modify == iteration_) return c.value;  // already brought up to date in this iteration
  c.backupValue = c.value;
  c.backupModify = c.modify;
  if (nTouched_ == touched_.size()) [[unlikely]] touched_.resize(2 * touched_.size());
  touched_[nTouched_++] = {stream, index};
  if (c.modify == kNeverRead) [[unlikely]] {
    c.value = firstRead(stream, index);
  } else if (largeStep_) {
    c.value = rng_.uniform();
  } else {
    if (c.modify < lastLargeStep_) {
      c.value = rng_.uniform();
      c.modify = lastLargeStep_;
    }
    const int64_t n = iteration_ - c.modify;
    if (n == 1 && singleStepInline_) c.value = step(c.value, rng_.nextU32());  // == mutate(c.value, 1)
    else if (n > 0) c.value = mutate(c.value, n);
  }
  c.modify = iteration_;
  return c.value;
}

// The rare paths, kept out of readImpl so that its common path stays short.
[[gnu::noinline, gnu::cold]] KelemenSource::Coord& KelemenSource::grow(int stream, int index) {
  coords_[stream].resize(static_cast<size_t>(index) + 1);
  return coords_[stream][index];
}
// Iteration 0 replays the bootstrap candidate; later, an unread coordinate of the current state is an
// independent uniform (see the header), drawn from the chain's own stream.
[[gnu::noinline]] float KelemenSource::firstRead(int stream, int index) {
  return iteration_ == 0 ? candidate_.valueAt(stream, index) : rng_.uniform();
}

float KelemenSource::read(int stream, int index) { return readImpl(stream, index); }

void KelemenSource::write(int stream, int index, float value) {
  std::vector<Coord>& v = coords_[stream];
  Coord& c = static_cast<size_t>(index) < v.size() ? v[index] : grow(stream, index);
  if (c.modify != iteration_) {
    c.backupValue = c.value;
    c.backupModify = c.modify;
    if (nTouched_ == touched_.size()) touched_.resize(2 * touched_.size());
    touched_[nTouched_++] = {stream, index};
  }
  c.value = value;
  c.modify = iteration_;
}
// The common cases without a call (no registers to save), exactly as readImpl() treats them: a coordinate
// already current; in a small step, one that was current in the previous iteration (one step); in a
// large step, any coordinate read before (a fresh uniform).
[[gnu::always_inline]] inline float KelemenSource::readFast(int stream, int index) {
  std::vector<Coord>& v = coords_[stream];
  if (static_cast<size_t>(index) < v.size()) [[likely]] {
    Coord& c = v[index];
    if (c.modify == iteration_) return c.value;
    if (nTouched_ < touched_.size()) [[likely]] {
      // c.modify >= lastLargeStep_ >= 0 excludes kNeverRead (and iteration 0).
      const bool oneStep = !largeStep_ && singleStepInline_ && c.modify == iteration_ - 1 && c.modify >= lastLargeStep_;
      const bool redraw = largeStep_ && c.modify != kNeverRead;
      if (oneStep || redraw) {
        c.backupValue = c.value;
        c.backupModify = c.modify;
        touched_[nTouched_++] = {stream, index};
        c.value = redraw ? rng_.uniform() : step(c.value, rng_.nextU32());
        c.modify = iteration_;
        return c.value;
      }
    }
  }
  return readSlow(stream, index);
}
[[gnu::noinline]] float KelemenSource::readSlow(int stream, int index) { return readImpl(stream, index); }
float KelemenSource::next1D() { return readFast(stream_, next_++); }
Vec2 KelemenSource::next2D() {
  const int index = next_;
  next_ += 2;
  const float a = readFast(stream_, index);
  return {a, readFast(stream_, index + 1)};
}

// Kelemen et al. 2002, sec. 6, Mutate(): dv = s2 * exp(-log(s2/s1) * U), random sign, wrap.
// One 32-bit draw: bit 31 is the sign, the low 24 bits are U (table index + interpolation weight).
// Branch-free on the sign (a coin flip the predictor cannot learn): v - dv is computed as v + (-dv),
// which IEEE 754 defines to be the same number; each wrap test can only fire for its own sign (v + dv >= 0
// and v - dv < 1 for v in [0, 1)), so the results are those of the two-branch form bit for bit.
[[gnu::always_inline]] inline float KelemenSource::step(float v, uint32_t bits) const {
  const uint32_t u24 = bits & 0xffffffu;
  const uint32_t idx = u24 >> 14;  // 10 bits: kStepTable = 1024
  const float frac = float(u24 & 0x3fffu) * (1.0f / 16384.0f);
  const float dv = stepTable_[idx] + frac * stepDiff_[idx];
  const float sdv = std::bit_cast<float>(std::bit_cast<uint32_t>(dv) ^ (~bits & 0x80000000u));  // bit 31 set: +dv
  v += sdv;
  if (v >= 1) [[unlikely]] {
    v -= 1;
  } else if (v < 0) [[unlikely]] {
    v += 1;
    if (v >= 1) v = 0;  // -tiny + 1 rounds to 1.0f
  }
  return v;
}

float KelemenSource::mutate(float v, int64_t n) {
  if (params_.kernel == SmallStepKernel::Gaussian) {
    // Box-Muller; sum of n N(0, sigma^2) steps = N(0, n sigma^2).
    const double u1 = 1.0 - rng_.uniformDouble(), u2 = rng_.uniformDouble();
    const double z = std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
    return wrap01(double(v) + params_.sigma * std::sqrt(double(n)) * z);
  }
  if (n >= uniformAfter_) return rng_.uniform();
  for (int64_t i = 0; i < n; ++i) v = step(v, rng_.nextU32());
  return v;
}

std::vector<float> KelemenSource::storedValues(int stream) const {
  std::vector<float> out;
  out.reserve(coords_[stream].size());
  for (const Coord& c : coords_[stream]) out.push_back(c.value);
  return out;
}

}  // namespace mlt
