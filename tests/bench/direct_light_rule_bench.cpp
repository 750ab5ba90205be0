// The direct-light rule's pilot (common/job/direct_light_rule.h) on every bundled scene at 256x256, at the
// scene's own max depth: its share, CV, time and choice per seed. The thresholds of the rule were read
// from this table next to docs/CHAINS.md's measurements of --separate-direct.
//   usage: direct_light_rule_bench [seeds (default 5)]
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "common/job/direct_light_rule.h"
#include "common/render/render_scene.h"
#include "common/scene/scene_loader.h"

int main(int argc, char** argv) {
  using namespace mlt;
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 5;
  const std::vector<std::string> scenes = {"cornell-box.xml",    "checker-spheres.pbrt", "textured-serialized.xml",
                                           "cornell-spheres.xml", "caustic-mirror.xml",  "door-ajar.xml",
                                           "glossy-plates.xml"};
  std::printf("%-24s %5s %8s %8s %7s %9s %s\n", "scene", "seed", "share", "CV", "samples", "ms", "separate");
  for (const std::string& name : scenes) {
    SceneDesc desc = loadScene(std::string(MLTFARM_SOURCE_DIR) + "/scenes/" + name);
    desc.camera.width = desc.camera.height = 256;
    const std::unique_ptr<RenderScene> scene = RenderScene::build(desc);
    RenderSettings s;
    s.method = "mmlt";
    s.width = s.height = 256;
    s.integrator.maxDepth = desc.maxDepth.value_or(s.integrator.maxDepth);
    for (int seed = 1; seed <= seeds; ++seed) {
      s.seed = uint64_t(seed);
      const DirectLightPilot p = directLightPilot(*scene, s);
      const std::string cv = p.cv >= 0 ? fmt::format("{:8.2f}", p.cv) : std::string("       -");  // not drawn
      std::printf("%-24s %5d %8.3f %s %7d %9.1f %s\n", name.c_str(), seed, p.share, cv.c_str(), int(p.samples),
                  p.seconds * 1e3, p.separate ? "yes" : "no");
    }
  }
  return 0;
}
