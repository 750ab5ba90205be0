// The local farm behind `mltfarm render` (the default mode): starts a coordinator and W worker processes
// on loopback (W = cores by default), submits the scene, reports progress, fetches OUT.exr (+ OUT.png)
// and shuts everything down. The coordinator listens on 127.0.0.1 with an ephemeral port and a random
// token, so nothing else on the machine can use it; its state directory is temporary unless given.
#pragma once
#include <functional>
#include <string>

#include "common/farm/farm_types.h"
#include "proto/convert.h"

namespace mlt::farm {

struct EmbeddedFarmOptions {
  std::string scenePath;
  wire::SubmittedSettings settings;
  int workers = 0;               // worker processes; 0 = hardware concurrency
  int threadsPerWorker = 1;
  std::string outExr, outPng;    // empty outPng: no PNG
  std::string stateDir;          // empty: a temporary directory, removed afterwards
  bool keepLogs = false;         // keep the temporary directory (logs) even on success
  std::function<void(const JobStatus&)> onStatus;  // progress (WatchJob stream)
  // Runs once the image is fetched, while the coordinator and the workers, already told to stop, exit
  // (e.g. the caller's PNG from OUT.exr): their shutdown overlaps it instead of preceding it. What it
  // throws reaches the caller after the farm has exited and its temporary state is removed.
  std::function<void()> afterFetch;
};

struct EmbeddedFarmResult {
  JobStatus status;              // final status (Done)
  double seconds = 0;            // submit -> done
  double startupSeconds = 0;     // processes up and registered
  std::string stateDir;
};

// Throws std::runtime_error (with the coordinator's message, e.g. the loader's error) on failure.
EmbeddedFarmResult runEmbeddedFarm(const EmbeddedFarmOptions& options);

}  // namespace mlt::farm
