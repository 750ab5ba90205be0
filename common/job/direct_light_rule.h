// Whether a chain job renders its direct light with a pass of its own (separateDirect; a pt pass,
// kDirectPassMethod in mlt_job.h) when the settings leave the choice to the plan (DirectLight::Auto).
//
// The pass helps where a pixel estimate of the direct light is smooth, and hurts where it is spiky:
// measured at the results page's protocol (docs/CHAINS.md, "--separate-direct"; then with a bdpt pass, and
// again with the pt pass: glossy-plates 2.0-3.1x, door-ajar 1.2-1.4x for mmlt and veach-mlt), it lowered mmlt's and
// veach-mlt's relMSE on the Cornell box, checker-spheres, textured-serialized and cornell-spheres (large
// lights over diffuse or textured surfaces) and raised it on glossy-plates (small lights in glossy
// reflections), door-ajar (light through a gap) and caustic-mirror (no direct light to render at all).
// A chain spends its mutations where the image is bright, so it does well on a highlight that a pixel
// estimator samples badly, and badly in the dark pixels a smooth pixel estimator gets right.
//
// A pilot tells the two apart before the job is planned, with bdpt samples (the pass's estimator until
// the pt pass replaced it; the thresholds below were fitted with them, and classify the bundled scenes
// the same way for the pt pass):
//   - kPilotShareSamples samples at the job's max depth give the share of the light in paths of at most
//     kDirectMaxSegments segments: share = sum_i d_i / sum_i (d_i + r_i), d_i and r_i the luminance of
//     sample i's short and longer paths;
//   - kPilotCvSamples samples limited to kDirectMaxSegments give the one-bounce light's coefficient of
//     variation per sample within kPilotStrata x kPilotStrata film tiles g (sample i in tile i mod G):
//         CV^2 = sum_g sum_{i in g} (x_i - xbar_g)^2 / (N xbar^2),   x_i = sample i's one-bounce luminance.
//     The tiles leave out how the image varies from place to place (the pass's pixels each estimate their
//     own mean); what is left is the noise the pass would show. Emission seen directly (one segment) is
//     left out of the CV: the pass renders it nearly without noise, however bright the light's pixels.
// The pass is taken when share >= kDirectMinShare and CV <= kDirectMaxCv. The pilot draws only what can
// change the choice (it counts as part of the bootstrap, whose share of a 4-s job it was ~1%):
//   - the share's first kPilotShareFirst samples stop it when they put the share below kPilotShareStop, a
//     third of the threshold (caustic-mirror: no direct light at all, and its long paths made the share's
//     samples 80% of the pilot's time). With 1024 samples the Cornell box's share ranged 64-83% over 8
//     seeds (next paragraph), so stopping below 10% takes an error twice that spread to miss a scene at
//     30%; and a wrong stop costs a pass, not correctness: either choice is unbiased;
//   - the CV samples are drawn only for a share of at least kDirectMinShare (not for door-ajar's ~15%);
//   - a pilot that only sizes a pass the settings asked for (PilotUse::SizePass) draws the share's samples
//     alone, all of them.
// The share is summed in sample order either way, so it is the same number, bit for bit, whether or not
// the pilot could have stopped early.
// The thresholds come from the bundled scenes at 256x256 (tests/bench/direct_light_rule_bench, 10 seeds;
// docs/CHAINS.md): the scenes the pass helped have share 0.67-0.91 and CV 0.5-4.7 (cornell-spheres'
// largest), the scenes it hurt CV 8.3 and more (glossy-plates' smallest), share 0.16 (door-ajar, CV
// 6.5-7.1) or no direct light at all (caustic-mirror). The pilot is a pure function of the scene, the
// seed, the film and the integrator settings (not of the thread count), so the resolved choice given
// explicitly reproduces the job.
// The share also sizes the pass (mlt_job.h, directSppPerMutation), in its odds s / (1 - s), which is why
// it takes 4096 samples: with 1024 the Cornell box's share ranged 64-83% over 8 seeds (a pass of 18 to 48
// samples per 100 mutations per pixel), with 4096 74.1-79.8% over 3, with 8192 75.7-77.6% over 6. The
// pilot costs 0.03-0.055 s of one thread at 256x256 on the bundled scenes; it counts as part of the
// bootstrap.
#pragma once
#include <cstdint>

#include "common/settings/render_settings.h"

namespace mlt {

class RenderScene;

constexpr uint64_t kPilotShareSamples = 4096;  // at the job's max depth
constexpr uint64_t kPilotShareFirst = 1024;    // of those, before the pilot may stop (PilotUse::Decide)
constexpr double kPilotShareStop = 0.1;        // ... when their share is below this
constexpr uint64_t kPilotCvSamples = 16384;    // at kDirectMaxSegments
constexpr int kPilotStrata = 32;
constexpr double kDirectMinShare = 0.3;
constexpr double kDirectMaxCv = 6.0;

// What the pilot is run for: to choose (DirectLight::Auto) or only to size a pass already chosen (its share).
enum class PilotUse { Decide, SizePass };

struct DirectLightPilot {
  uint64_t samples = 0;  // drawn in all
  double share = 0;    // of the pilot's luminance, in paths of at most kDirectMaxSegments segments
  double cv = -1;      // the direct estimate's CV per sample, within film strata; -1: not measured
  double seconds = 0;  // wall time of the pilot
  bool decided = false;   // run with PilotUse::Decide: `separate` is the rule's choice
  bool separate = false;  // the rule's choice: share >= kDirectMinShare && cv <= kDirectMaxCv
};

// Runs the pilot on all threads of the calling arena (the result does not depend on how many).
DirectLightPilot directLightPilot(const RenderScene& scene, const RenderSettings& settings,
                                  PilotUse use = PilotUse::Decide);

}  // namespace mlt
