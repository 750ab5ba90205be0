// `mltfarm merge PART.exr... -o OUT.exr [--png OUT.png]`: merges partial-film EXRs written by the
// coordinator (--keep-partials) offline. Checks that they belong together (same job, scene hash, plan:
// b, size, method; no task twice; every task present, naming the missing ones) and writes the image
// byte-identical to the one the coordinator develops from the same tasks (coordinator/merge.h).
#include <memory>

#include "coordinator/merge.h"
#include "tools/cli/commands.h"

namespace mlt::cli {
namespace {

struct MergeOptions {
  std::vector<std::string> parts;
  std::string out, png;
};

const CommandRegistration kMerge("merge", "Merge partial-film EXRs offline into the final image", [](CLI::App& sub) -> CommandRun {
  auto o = std::make_shared<MergeOptions>();
  sub.add_option("parts", o->parts, "Partial-film EXRs (one per task)")->required();
  sub.add_option("-o,--output", o->out, "Output EXR")->required();
  sub.add_option("--png", o->png, "Also write a PNG preview");
  return [o] {
    farm::mergePartialExrs(o->parts, o->out, o->png);
    return 0;
  };
});

}  // namespace
}  // namespace mlt::cli
