// The in-process renderer: load a scene, plan the job, run every work unit in this process (TBB), merge
// in unit-index order, develop, write OUT.exr (+ OUT.png). `mltfarm render --in-process` is this
// function; the farm's local mode (coordinator + worker processes) is the other path and must produce the
// same image for the same settings, because both merge the same units in the same order.
#pragma once
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/io/exr_io.h"
#include "common/job/render_job.h"

namespace mlt::cli {

struct LocalRenderOptions {
  std::string scenePath;
  std::map<std::string, std::string> defines;   // Mitsuba -D name=value
  RenderSettings settings;                      // width/height 0 = the scene's film size
  std::optional<int> maxDepth, rrDepth;         // unset: the scene's <integrator> values, else defaults
  bool sppGiven = true;                         // false with a time budget: run until the time is up
  int threads = 0;                              // 0 = every core
  std::string outExr;                           // empty: write nothing
  std::string outPng;                           // empty: OUT.exr with the extension replaced by .png
  float exposureStops = 0;                      // PNG only
  bool showProgress = true;
  // bdpt: also write OUT_s<s>_t<t>.exr per technique (path lengths up to max depth, or 8 if unlimited);
  // the units then run one at a time (each still uses every thread).
  bool techniqueImages = false;
};

struct LocalRenderResult {
  JobPlan plan;                // the plan developed (time budget, pt/lt/bdpt: only the units that ran)
  PartialResult merged;
  std::vector<Color> image;    // developed linear RGB
  ImageMetadata metadata;
  std::string sceneHash;
  double seconds = 0;          // wall time of planning + rendering (not loading or writing)
};

LocalRenderResult renderLocal(const LocalRenderOptions& options);

// "out.exr" -> "out.png" (any extension replaced; none added if missing).
std::string pngPathFor(const std::string& exrPath);

}  // namespace mlt::cli
