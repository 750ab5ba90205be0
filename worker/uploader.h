// Worker -> coordinator calls that move bulk data: fetching a scene bundle and uploading a partial film
// as a client stream of chunks of at most 1 MiB (never relying on raising gRPC's 4 MiB limit).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "common/farm/farm_types.h"
#include "common/methods/registry.h"
#include "proto/channel.h"
#include "proto/convert.h"
#include "proto/mltfarm.grpc.pb.h"

namespace mlt::farm {

struct UploadTarget {
  std::string workerId, leaseId, jobId;
  uint32_t taskIndex = 0;
};

// Streams `result`; returns the coordinator's reply. Throws RpcError on a failed call. `chunks`, if
// given, receives the number of film chunks sent; `filmBytes` the film's size on the wire.
UploadReply uploadPartial(v1::WorkerService::Stub& stub, const ChannelOptions& o, const UploadTarget& target,
                          const PartialResult& result, size_t* chunks = nullptr, uint64_t* filmBytes = nullptr);

// Fetches a bundle by hash and checks that its content hashes to `sceneHash`.
std::vector<BundleFile> fetchScene(v1::WorkerService::Stub& stub, const ChannelOptions& o,
                                   const std::string& sceneHash);

// `bytes`, if given, receives the plan's size on the wire.
JobPlan fetchPlan(v1::WorkerService::Stub& stub, const ChannelOptions& o, const std::string& jobId,
                  uint64_t* bytes = nullptr);

}  // namespace mlt::farm
