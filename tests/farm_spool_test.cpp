// The worker's spool of finished films (worker/spool.h), without processes: bounded by its size, drained
// oldest first and stopping at the first film the coordinator cannot take yet, films kept bit-exact on
// disk and taken over by the next worker process when the one that wrote them is gone; a torn file is
// dropped, never uploaded.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "proto/convert.h"
#include "tests/support/temp_dir.h"
#include "worker/spool.h"

namespace mlt::farm {
namespace {

namespace fs = std::filesystem;

PartialResult film(uint32_t task) {
  PartialResult r;
  r.film = Film(16, 8);
  for (size_t i = 0; i < r.film.pixelCount(); i += 3) {
    r.film.pixelSums()[i] = {double(i) * 0.25, double(task), 1.0 / 1024};
    r.film.pixelCounts()[i] = double(i % 5);
    r.film.splatLayer(2)[i] = {0.5, double(i), 3.0};
  }
  r.samples = 1000 + task;
  r.units = {task};
  return r;
}

UploadTarget target(uint32_t task) { return {"w-1.abc", "l-" + std::to_string(task), "job-3", task}; }

size_t filesIn(const std::string& dir) {
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.is_regular_file();
  return n;
}

TEST(FarmSpool, BoundedBySizeDrainedInOrderStoppingAtTheFirstRetry) {
  TempDir tmpDir("farm_spool");
  const std::string root = tmpDir.path().string();
  const std::string dir = root + "/spool";
  // Room for three films of this size, not four.
  const uint64_t one = [&] {
    FilmSpool probe(root + "/probe", 1ull << 30);
    EXPECT_TRUE(probe.put(target(0), film(0)));
    return probe.bytes();
  }();
  FilmSpool spool(dir, 3 * one + one / 2);
  for (uint32_t t = 0; t < 3; ++t) EXPECT_TRUE(spool.put(target(t), film(t))) << t;
  EXPECT_FALSE(spool.put(target(3), film(3))) << "the spool must not exceed its size";
  EXPECT_EQ(spool.size(), 3u);
  EXPECT_LE(spool.bytes(), 3 * one + one / 2);
  EXPECT_EQ(filesIn(dir), 3u);
  EXPECT_EQ(spool.leaseIds("w-1.abc"), (std::vector<std::string>{"l-0", "l-1", "l-2"}));
  EXPECT_TRUE(spool.leaseIds("w-2.def").empty());

  // The coordinator takes the first and is gone for the second: the third is not tried.
  std::vector<uint32_t> tried;
  auto upload = [&](int goodBefore) {
    return [&tried, goodBefore](const UploadTarget& t, const PartialResult& r) {
      tried.push_back(t.taskIndex);
      EXPECT_EQ(wire::encodeFilm(r.film), wire::encodeFilm(film(t.taskIndex).film)) << "film changed on disk";
      EXPECT_EQ(r.samples, film(t.taskIndex).samples);
      EXPECT_EQ(r.units, film(t.taskIndex).units);
      return int(tried.size()) <= goodBefore ? FilmSpool::Outcome::Done : FilmSpool::Outcome::Retry;
    };
  };
  EXPECT_EQ(spool.drain(upload(1)), 1u);
  EXPECT_EQ(tried, (std::vector<uint32_t>{0, 1}));
  EXPECT_EQ(spool.size(), 2u);
  EXPECT_EQ(filesIn(dir), 2u);
  EXPECT_TRUE(spool.put(target(3), film(3))) << "room again";
  tried.clear();
  EXPECT_EQ(spool.drain(upload(100)), 3u);
  EXPECT_EQ(tried, (std::vector<uint32_t>{1, 2, 3}));
  EXPECT_EQ(spool.size(), 0u);
  EXPECT_EQ(spool.bytes(), 0u);
  EXPECT_EQ(filesIn(dir), 0u);
}

TEST(FarmSpool, FilmsOfAWorkerThatIsGoneAreTakenOverAndTornOnesDropped) {
  TempDir tmpDir("farm_spool");
  const std::string root = tmpDir.path().string();
  const std::string dir = root + "/spool";
  {
    FilmSpool spool(dir, 1ull << 30);
    EXPECT_TRUE(spool.put(target(5), film(5)));
    EXPECT_TRUE(spool.put(target(6), film(6)));
    EXPECT_TRUE(spool.put(target(9), film(9)));  // becomes the film of a process that runs
  }
  // The first two renamed as a process that no longer runs would have named them (no pid is that high).
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_EQ(files.size(), 3u);
  fs::rename(files[0], fs::path(dir) / "2147483000-0.film");
  fs::rename(files[1], fs::path(dir) / "2147483000-1.film");
  const fs::path alive = fs::path(dir) / (std::to_string(getppid()) + "-0.film");
  fs::rename(files[2], alive);
  // A third film of that process, torn (cut short as a power loss might leave it).
  fs::copy_file(fs::path(dir) / "2147483000-1.film", fs::path(dir) / "2147483000-2.film");
  fs::resize_file(fs::path(dir) / "2147483000-2.film", fs::file_size(fs::path(dir) / "2147483000-2.film") / 2);
  FilmSpool next(dir, 1ull << 30);
  EXPECT_EQ(next.size(), 2u);
  std::vector<uint32_t> tried;
  next.drain([&](const UploadTarget& t, const PartialResult& r) {
    tried.push_back(t.taskIndex);
    EXPECT_EQ(t.workerId, "w-1.abc");
    EXPECT_EQ(t.leaseId, "l-" + std::to_string(t.taskIndex));
    EXPECT_EQ(t.jobId, "job-3");
    EXPECT_EQ(wire::encodeFilm(r.film), wire::encodeFilm(film(t.taskIndex).film));
    return FilmSpool::Outcome::Done;
  });
  EXPECT_EQ(tried, (std::vector<uint32_t>{5, 6}));
  EXPECT_EQ(filesIn(dir), 1u) << "the torn film is removed, the delivered ones too; the running process's stays";
  EXPECT_TRUE(fs::exists(alive));
}

}  // namespace
}  // namespace mlt::farm
