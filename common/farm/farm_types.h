// Domain types of the farm protocol (no protobuf): what the coordinator's handlers and the worker's
// client (worker/coordinator_client.h) speak. proto/farm_convert.cpp translates them to the wire; the
// render job values themselves go through proto/convert.h.
#pragma once
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/methods/registry.h"

namespace mlt::farm {

// An error a handler reports to a remote caller; the service maps `code` onto a gRPC status code.
class FarmError : public std::runtime_error {
 public:
  enum class Code { InvalidArgument, NotFound, FailedPrecondition, AlreadyExists, Unauthenticated, Internal,
                    Unavailable, ResourceExhausted };  // ResourceExhausted: the coordinator's disk is full
  FarmError(Code code, const std::string& what) : std::runtime_error(what), code_(code) {}
  Code code() const { return code_; }
 private:
  Code code_;
};

enum class JobState { Queued = 1, Planning = 2, Running = 3, Merging = 4, Done = 5, Failed = 6, Cancelled = 7 };
const char* jobStateName(JobState s);
inline bool isTerminal(JobState s) { return s == JobState::Done || s == JobState::Failed || s == JobState::Cancelled; }

struct JobStatus {
  std::string jobId, name;
  JobState state = JobState::Queued;
  std::string phase;
  int priority = 0;
  std::string method, sceneHash;
  int width = 0, height = 0;
  double b = 0, bStdErr = 0;
  uint64_t workDone = 0, workTotal = 0;
  uint32_t unitsDone = 0, unitsTotal = 0, tasksDone = 0, tasksTotal = 0, leasedTasks = 0;
  double etaSeconds = -1, elapsedSeconds = 0, bootstrapSeconds = 0;
  std::string error;
  uint32_t failedAttempts = 0;  // failure reports + lease expiries (since this coordinator started)
  uint64_t version = 0;  // bumped on every change (WatchJob waits on it); not sent
};

// A file of a scene bundle: path relative to the bundle root ('/'-separated, no "..").
struct BundleFile {
  std::string path;
  std::string data;
};

struct SubmitRequest {
  RenderSettings settings;
  bool hasSize = false, hasMaxDepth = false, hasRrDepth = false, hasSpp = false;
  std::map<std::string, std::string> defines;  // scene parameters (Mitsuba -D)
  int priority = 0;
  std::string name;
  // Either a bundle (sceneFile is its path inside the bundle) or a coordinator-readable path.
  std::vector<BundleFile> bundle;
  std::string bundleSceneFile;
  std::string coordinatorPath;
  std::string bundleHash;  // the client's hash of the bundle; checked if set
  std::string client;      // who submits (the transport's peer host): jobs-per-client quota
};

// A lease: a fixed, contiguous range of work units [unitBegin, unitEnd) of one job (a "task").
struct Lease {
  std::string leaseId, jobId;
  uint32_t taskIndex = 0, unitBegin = 0, unitEnd = 0;
  std::string sceneHash, sceneFile;
  std::map<std::string, std::string> defines;  // the scene is loaded with these parameters
};

struct WorkerInfo {
  std::string hostname;
  int threads = 1;
  int64_t pid = 0;
};

struct Registration {
  std::string workerId;
  double heartbeatSeconds = 1, leaseTimeoutSeconds = 10;
};

struct HeartbeatReply {
  bool unknownWorker = false;
  std::vector<std::string> cancelledLeases;
};

struct FailureReply {
  bool jobFailed = false;
};

struct UploadReply {
  bool accepted = false;
  std::string message;
};

}  // namespace mlt::farm
