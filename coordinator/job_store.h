// The coordinator's persistent job table: an embedded SQLite database (`STATE_DIR/farm.db`) holding job
// records and each job's plan, written on every state change (a few rows per job, off the hot path).
// Accepted task results live beside it as files (result_store.h). Not thread-safe: the caller
// serializes access.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

struct sqlite3;

namespace mlt::farm {

struct JobRecord {
  int64_t id = 0;
  std::string name;
  int priority = 0;
  int state = 0;                 // JobState
  std::string settings;          // serialized mltfarm.v1.RenderSettings (as submitted, scene defaults applied)
  std::string sceneHash, sceneFile;
  std::string plan;              // serialized mltfarm.v1.JobPlan; empty until planned
  uint32_t tasks = 0;
  std::string error;
  double submittedAt = 0;        // unix seconds
  std::string client;            // who submitted it (the peer host): the jobs-per-client quota; "" if unknown
};

class JobStore {
 public:
  // Creates the schema if needed, and adds the columns a database from an earlier version lacks (additive:
  // such a database opens, its jobs have no client). Throws std::runtime_error.
  explicit JobStore(const std::string& path);
  ~JobStore();
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  int64_t insertJob(const JobRecord& r);       // returns the new id
  void updateState(int64_t id, int state, const std::string& error);
  void setPlan(int64_t id, const std::string& plan, uint32_t tasks, int state);
  std::vector<JobRecord> loadJobs();
  void deleteJob(int64_t id);

 private:
  void exec(const char* sql);
  bool hasColumn(const char* table, const std::string& column);
  sqlite3* db_ = nullptr;
  std::string path_;
};

}  // namespace mlt::farm
