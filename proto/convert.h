// The one conversion file between the wire (proto/mltfarm.proto) and the domain types of
// common/methods/registry.h. FromProto validates every range and throws WireError naming the field;
// the services turn it into INVALID_ARGUMENT. Nothing outside coordinator/, worker/ and the farm
// subcommands includes this header.
#pragma once
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/methods/registry.h"
#include "proto/mltfarm.pb.h"

namespace mlt {
namespace v1 = ::mltfarm::v1;  // the wire's protobuf package
}  // namespace mlt

namespace mlt::wire {

// Bumped whenever a message changes meaning. Every message that crosses processes carries it.
inline constexpr uint32_t kFormatVersion = 3;  // 2: b's tail split (TargetSums.bulk, BootstrapEstimate.tau); 3: chain layers 1 + 2k, b strata 2 + 2k
// Largest piece of a streamed film, bundle or result (gRPC's default receive limit is 4 MiB).
inline constexpr size_t kMaxChunkBytes = 1 << 20;

// Invalid input from the wire: `field` names the offending field ("settings.width").
class WireError : public std::invalid_argument {
 public:
  WireError(const std::string& field, const std::string& what)
      : std::invalid_argument(field + ": " + what), field_(field) {}
  const std::string& field() const { return field_; }
 private:
  std::string field_;
};

// Throws WireError unless version == kFormatVersion.
void checkVersion(uint32_t version, const char* message);

// Settings as submitted: which optional fields the client set.
struct SubmittedSettings {
  RenderSettings settings;
  bool hasSize = false, hasMaxDepth = false, hasRrDepth = false, hasSpp = false;
  std::map<std::string, std::string> defines;  // Mitsuba -D name=value (scene parameters)
};
// Throws WireError unless every define has a valid name (letters, digits, '_'; at most 128 characters)
// and value (at most 4096 bytes, no NUL), and there are at most 256 of them.
void validateDefines(const std::map<std::string, std::string>& defines, const char* field);
v1::RenderSettings toProto(const SubmittedSettings& s);
// Fully resolved settings (every flag set).
v1::RenderSettings toProto(const RenderSettings& s);
SubmittedSettings fromProto(const v1::RenderSettings& p);  // validates ranges

v1::JobPlan toProto(const JobPlan& plan);
JobPlan fromProto(const v1::JobPlan& p);                  // validates

v1::TargetSums toProto(const TargetSums& t);
TargetSums fromProto(const v1::TargetSums& p, const char* field);  // validates
v1::ChainStats toProto(const ChainStats& s);
ChainStats fromProto(const v1::ChainStats& p);

// A PartialResult travels as a header (everything but the raw sums) + the film's raw bytes.
v1::PartialHeader partialHeader(const PartialResult& r);
// Raw film bytes: pixel sums (3 doubles/pixel), pixel counts (1 double/pixel), then the sums of every
// allocated splat layer in ascending order (3/pixel each; Film::splatLayers lists them, layer 0 always),
// little-endian IEEE-754, row-major. Exact: decode(encode(f)) has the same bits.
inline constexpr uint32_t kMaxSplatLayer = 3075;  // mlt/develop.h largeStepLayer(1024, 1025): max depth <= 1024
std::string encodeFilm(const Film& film);
// A zero film of that size with those splat layers, checked as decodeFilm checks them (WireError).
Film zeroFilm(int width, int height, uint64_t nonFinite, const std::vector<uint32_t>& layers);
Film decodeFilm(int width, int height, const std::string& bytes, uint64_t nonFinite,
                const std::vector<uint32_t>& layers = {0});
size_t filmByteSize(int width, int height, size_t splatLayers = 1);
// The header's splat layers ({0} when it lists none).
std::vector<uint32_t> headerLayers(const v1::PartialHeader& h);
// Decodes the film as h.film_encoding says (raw or zero runs); validates.
PartialResult fromProto(const v1::PartialHeader& h, const std::string& filmBytes);
// The header alone as bytes (partial EXR metadata) and back, with the film supplied separately.
std::string partialHeaderBytes(const PartialResult& r);
PartialResult partialFromHeaderBytes(const std::string& headerBytes, Film film);  // validates the size

// Whole PartialResult as one blob (header length + header + film bytes): the coordinator's result files
// use it, with the film's zero runs left out (zeroRuns, proto/sparse_film.h).
std::string serializePartial(const PartialResult& r, bool zeroRuns = false);
PartialResult parsePartial(const std::string& blob);

std::string jobPlanBytes(const JobPlan& plan);           // deterministic serialization
std::string deterministicBytes(const google::protobuf::MessageLite& m);  // maps in key order
JobPlan parseJobPlan(const std::string& bytes);

}  // namespace mlt::wire
