// `mltfarm render` through the local farm (the default): a coordinator and W worker processes on
// loopback, started, fed the scene, and shut down again (coordinator/embedded.h). Writes OUT.exr and
// OUT.png like the in-process renderer, with the same metadata keys; the image does not depend on W.
#pragma once
#include "common/io/exr_io.h"
#include "tools/cli/render_local.h"

namespace mlt::cli {

// workers: worker processes (0 = one with every thread). farmDir: where the farm keeps its state and
// logs (empty: a temporary directory, removed when the job succeeds).
// Returns the image written to options.outExr (read back once, for the PNG), or an empty one if none.
ExrImage renderWithLocalFarm(const LocalRenderOptions& options, int workers, const std::string& farmDir = "");

}  // namespace mlt::cli
