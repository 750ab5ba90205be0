// Farm protocol types <-> wire (the coordinator/worker boundary's conversion file; render job values
// go through proto/convert.h). Validation errors are wire::WireError naming the field.
#pragma once
#include "common/farm/farm_types.h"
#include "proto/convert.h"
#include "proto/mltfarm.pb.h"

namespace mlt::farm {

v1::JobStatus toProto(const JobStatus& s);
JobStatus fromProto(const v1::JobStatus& p);
v1::Lease toProto(const Lease& l);
Lease fromProto(const v1::Lease& p);
// The submit header with the bundle files already assembled from the chunks.
SubmitRequest fromProto(const v1::SubmitHeader& h, std::vector<BundleFile> files);

}  // namespace mlt::farm
