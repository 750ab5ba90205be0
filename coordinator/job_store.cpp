// SQLite persistence of jobs and plans (see job_store.h).
#include "coordinator/job_store.h"

#include <sqlite3.h>

#include <fmt/format.h>
#include <stdexcept>

#include "common/farm/farm_types.h"

namespace mlt::farm {
namespace {

// A failed SQLite call as the status its caller answers: a full disk is RESOURCE_EXHAUSTED, a database
// that cannot be written (read-only, I/O error, locked) UNAVAILABLE, anything else INTERNAL.
[[noreturn]] void throwSqlite(sqlite3* db, const std::string& message) {
  using Code = FarmError::Code;
  const int rc = db ? (sqlite3_extended_errcode(db) & 0xff) : SQLITE_NOMEM;
  Code code = Code::Internal;
  if (rc == SQLITE_FULL) code = Code::ResourceExhausted;
  else if (rc == SQLITE_READONLY || rc == SQLITE_IOERR || rc == SQLITE_CANTOPEN || rc == SQLITE_BUSY ||
           rc == SQLITE_LOCKED || rc == SQLITE_PERM || rc == SQLITE_NOMEM)
    code = Code::Unavailable;
  throw FarmError(code, message);
}

class Stmt {
 public:
  Stmt(sqlite3* db, const char* sql, const std::string& path) : db_(db), path_(path) {
    if (sqlite3_prepare_v2(db, sql, -1, &s_, nullptr) != SQLITE_OK) fail("prepare");
  }
  ~Stmt() { sqlite3_finalize(s_); }
  Stmt& bind(int i, int64_t v) { check(sqlite3_bind_int64(s_, i, v)); return *this; }
  Stmt& bind(int i, double v) { check(sqlite3_bind_double(s_, i, v)); return *this; }
  Stmt& bindText(int i, const std::string& v) {
    check(sqlite3_bind_text(s_, i, v.data(), int(v.size()), SQLITE_TRANSIENT));
    return *this;
  }
  Stmt& bindBlob(int i, const std::string& v) {
    check(sqlite3_bind_blob64(s_, i, v.data(), v.size(), SQLITE_TRANSIENT));
    return *this;
  }
  bool step() {  // true while a row is available
    int rc = sqlite3_step(s_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    fail("step");
    return false;
  }
  int64_t i64(int c) { return sqlite3_column_int64(s_, c); }
  double dbl(int c) { return sqlite3_column_double(s_, c); }
  std::string str(int c) {
    const void* p = sqlite3_column_blob(s_, c);
    int n = sqlite3_column_bytes(s_, c);
    return p ? std::string(static_cast<const char*>(p), size_t(n)) : std::string();
  }

 private:
  void check(int rc) { if (rc != SQLITE_OK) fail("bind"); }
  [[noreturn]] void fail(const char* what) {
    throwSqlite(db_, fmt::format("{}: sqlite {}: {}", path_, what, sqlite3_errmsg(db_)));
  }
  sqlite3* db_;
  sqlite3_stmt* s_ = nullptr;
  std::string path_;
};

}  // namespace

JobStore::JobStore(const std::string& path) : path_(path) {
  if (sqlite3_open(path.c_str(), &db_) != SQLITE_OK) {
    std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    throw std::runtime_error(fmt::format("{}: cannot open database: {}", path, msg));
  }
  sqlite3_busy_timeout(db_, 5000);
  // WAL + synchronous=FULL: a commit (a job submitted, planned, done) is on disk when it returns, even
  // through a power loss; NORMAL would survive only a killed process. Accepted results are files
  // (result_store.h), written durably too.
  exec("PRAGMA journal_mode=WAL");
  exec("PRAGMA synchronous=FULL");
  exec("CREATE TABLE IF NOT EXISTS jobs("
       " id INTEGER PRIMARY KEY AUTOINCREMENT, name TEXT, priority INTEGER, state INTEGER,"
       " settings BLOB, scene_hash TEXT, scene_file TEXT, plan BLOB, tasks INTEGER, error TEXT,"
       " submitted_at REAL, client TEXT NOT NULL DEFAULT '')");
  // Migrations: columns added since the table was first created.
  if (!hasColumn("jobs", "client")) exec("ALTER TABLE jobs ADD COLUMN client TEXT NOT NULL DEFAULT ''");
}

bool JobStore::hasColumn(const char* table, const std::string& column) {
  Stmt s(db_, fmt::format("PRAGMA table_info({})", table).c_str(), path_);
  while (s.step())
    if (s.str(1) == column) return true;
  return false;
}

JobStore::~JobStore() { sqlite3_close(db_); }

void JobStore::exec(const char* sql) {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql, nullptr, nullptr, &err) != SQLITE_OK) {
    std::string msg = err ? err : "?";
    sqlite3_free(err);
    throwSqlite(db_, fmt::format("{}: sqlite: {} ({})", path_, msg, sql));
  }
}

int64_t JobStore::insertJob(const JobRecord& r) {
  Stmt s(db_, "INSERT INTO jobs(name, priority, state, settings, scene_hash, scene_file, plan, tasks, error,"
              " submitted_at, client) VALUES(?,?,?,?,?,?,?,?,?,?,?)", path_);
  s.bindText(1, r.name).bind(2, int64_t(r.priority)).bind(3, int64_t(r.state)).bindBlob(4, r.settings)
      .bindText(5, r.sceneHash).bindText(6, r.sceneFile).bindBlob(7, r.plan).bind(8, int64_t(r.tasks))
      .bindText(9, r.error).bind(10, r.submittedAt).bindText(11, r.client);
  s.step();
  return sqlite3_last_insert_rowid(db_);
}

void JobStore::updateState(int64_t id, int state, const std::string& error) {
  Stmt s(db_, "UPDATE jobs SET state=?, error=? WHERE id=?", path_);
  s.bind(1, int64_t(state)).bindText(2, error).bind(3, id);
  s.step();
}

void JobStore::setPlan(int64_t id, const std::string& plan, uint32_t tasks, int state) {
  Stmt s(db_, "UPDATE jobs SET plan=?, tasks=?, state=? WHERE id=?", path_);
  s.bindBlob(1, plan).bind(2, int64_t(tasks)).bind(3, int64_t(state)).bind(4, id);
  s.step();
}

void JobStore::deleteJob(int64_t id) {
  Stmt s(db_, "DELETE FROM jobs WHERE id=?", path_);  // AUTOINCREMENT: the id is never given out again
  s.bind(1, id);
  s.step();
}

std::vector<JobRecord> JobStore::loadJobs() {
  Stmt s(db_, "SELECT id, name, priority, state, settings, scene_hash, scene_file, plan, tasks, error,"
              " submitted_at, client FROM jobs ORDER BY id", path_);
  std::vector<JobRecord> out;
  while (s.step()) {
    JobRecord r;
    r.id = s.i64(0);
    r.name = s.str(1);
    r.priority = int(s.i64(2));
    r.state = int(s.i64(3));
    r.settings = s.str(4);
    r.sceneHash = s.str(5);
    r.sceneFile = s.str(6);
    r.plan = s.str(7);
    r.tasks = uint32_t(s.i64(8));
    r.error = s.str(9);
    r.submittedAt = s.dbl(10);
    r.client = s.str(11);
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace mlt::farm
