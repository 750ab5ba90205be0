// The offline merge (`mltfarm merge`) trusts nothing it reads (issue 13): every size and count a partial
// claims is checked against the plan before pixels are allocated (a 8192x8192 header for a 16x16 job
// fails at once in 1 GB of address space), the raw sums carry a checksum (a partial passed through
// float is refused), `-o` may not name an input, outputs are renamed into place, and only regular files
// are read (a FIFO is refused, not opened).
#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstring>

#include <filesystem>
#include <fmt/format.h>

#include "common/farm/scene_loading.h"
#include "common/io/exr_io.h"
#include "coordinator/merge.h"
#include "proto/convert.h"
#include "tests/farm/farm_harness.h"

namespace mlt::farm::test {
namespace {

std::string toHex(const std::string& bytes) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  for (unsigned char c : bytes) out += {digits[c >> 4], digits[c & 15]};
  return out;
}

// Writes `bytes` to `path`.
void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// The message of the exception `f` throws ("" if none).
template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// A 16x16 path-traced job's partial EXRs, one per task, written as the coordinator writes them.
class MergeGuard : public ::testing::Test {
 protected:
  void SetUp() override {
    RenderSettings s;
    s.method = "pt";
    s.seed = 7;
    s.width = s.height = 16;
    s.spp = 8;
    s.samplesPerUnit = 4;  // sums of 4 float samples per pixel: not all representable in float
    s.integrator.maxDepth = 3;
    auto scene = buildRenderScene(loadSceneDesc(cornellBox()), s.width, s.height);
    plan_ = planJob(*scene, s);
    const std::vector<TaskRange> tasks = splitTasks(plan_);
    ASSERT_GE(tasks.size(), 2u);
    for (uint32_t t = 0; t < tasks.size(); ++t) {
      PartialResult r = emptyPartial(plan_);
      ASSERT_TRUE(runTask(*scene, plan_, tasks[t], r));
      parts_.push_back(dir_ / fmt::format("task-{:04}.exr", t));
      writePartialExr(parts_.back(), id_, plan_, t, r);
    }
  }
  // parts_ with part `i` replaced by a copy of it whose metadata `edit` changed (written by mltfarm's
  // own writer, so its checksum is right: only the claims differ).
  std::vector<std::string> withEditedPart(size_t i, const std::function<void(FilmExr&)>& edit) {
    FilmExr f = readFilmExr(parts_[i]);
    edit(f);
    std::vector<std::string> parts = parts_;
    parts[i] = dir_ / "edited.exr";
    writeFilmExr(parts[i], f.film, f.metadata, 1.0);
    return parts;
  }
  TempDir dir_;
  JobIdentity id_{"job-1", std::string(64, 'c'), "cornell-box.xml"};
  JobPlan plan_;
  std::vector<std::string> parts_;
};

TEST_F(MergeGuard, TheGoodPartsMergeAndTheOutputIsRenamedIntoPlace) {
  const std::string out = dir_ / "out.exr";
  mergePartialExrs(parts_, out, dir_ / "out.png");
  EXPECT_EQ(readExr(out).width, 16);
  EXPECT_TRUE(fs::exists(dir_ / "out.png"));
  for (const auto& e : fs::directory_iterator(dir_.path))
    EXPECT_EQ(e.path().string().find(".tmp-"), std::string::npos) << "left behind: " << e.path();
}

// A header claiming a 8192x8192 data window for the 16x16 job: refused from the header, in a process
// limited to 1 GB of address space (the pixels alone would take 3.7 GB).
TEST_F(MergeGuard, AHugeDataWindowFailsFastInSmallMemory) {
  std::string bytes = readFile(parts_[0]);
  for (const std::string attr : {"dataWindow", "displayWindow"}) {
    const size_t at = bytes.find(attr + '\0' + "box2i" + '\0');
    ASSERT_NE(at, std::string::npos);
    const size_t box = at + attr.size() + 1 + 6 + 4;  // name, type, size: then xmin ymin xmax ymax
    const int32_t max = 8191;
    std::memcpy(&bytes[box + 8], &max, 4);
    std::memcpy(&bytes[box + 12], &max, 4);
  }
  std::vector<std::string> parts = parts_;
  parts[0] = dir_ / "huge.exr";
  writeBytes(parts[0], bytes + std::string(1 << 16, '\0'));  // room for the longer line offset table
  std::string cmd = "ulimit -v 1000000; exec '" + toolsDir() + "/mltfarm' merge";
  for (const std::string& p : parts) cmd += " '" + p + "'";
  cmd += " -o '" + (dir_ / "huge-out.exr") + "'";
  ChildProcess merge({"/bin/bash", "-c", cmd}, dir_ / "merge-huge.log", false);
  const std::optional<int> rc = merge.wait(std::chrono::seconds(120));
  ASSERT_TRUE(rc.has_value());
  EXPECT_NE(*rc, 0);
  const std::string log = readFile(dir_ / "merge-huge.log");
  EXPECT_NE(log.find("data window 8192x8192 but the job's film is 16x16"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir_ / "huge-out.exr"));
}

TEST_F(MergeGuard, CountsAndPathLengthsAreCheckedAgainstThePlan) {
  // A plan unit with path_length 2^31-1.
  JobPlan bad = plan_;
  bad.units[0].pathLength = 2147483647;
  std::string e = errorOf([&] {
    mergePartialExrs(withEditedPart(0, [&](FilmExr& f) { f.metadata.strings["farm.plan"] = toHex(wire::jobPlanBytes(bad)); }),
                     dir_ / "o.exr", "");
  });
  EXPECT_NE(e.find("path_length"), std::string::npos) << e;
  // A task count that is not a count, and one the plan does not split into.
  e = errorOf([&] { mergePartialExrs(withEditedPart(1, [](FilmExr& f) { f.metadata.numbers["farm.tasks"] = 1e300; }), dir_ / "o.exr", ""); });
  EXPECT_NE(e.find("farm.tasks = 1e+300 is not a count"), std::string::npos) << e;
  const size_t tasks = splitTasks(plan_).size();
  e = errorOf([&] { mergePartialExrs(withEditedPart(1, [&](FilmExr& f) { f.metadata.numbers["farm.tasks"] = double(tasks + 1); }), dir_ / "o.exr", ""); });
  EXPECT_NE(e.find("but the plan splits into"), std::string::npos) << e;
  // A film of another size than the plan's (written consistently, checksum and all).
  e = errorOf([&] {
    mergePartialExrs(withEditedPart(0, [](FilmExr& f) { f.film = Film(17, 16); }), dir_ / "o.exr", "");
  });
  EXPECT_NE(e.find("data window 17x16 but the job's film is 16x16"), std::string::npos) << e;
  EXPECT_FALSE(fs::exists(dir_ / "o.exr"));
}

// An image tool read the partial and wrote it back, its sums passed through float: the checksum the
// writer stored no longer matches.
TEST_F(MergeGuard, SumsPassedThroughFloatAreRefused) {
  FilmExr f = readFilmExr(parts_[0]);
  const std::string original = readFile(parts_[0]);
  bool changed = false;
  for (RGBd& p : f.film.pixelSums())
    for (double* c : {&p.r, &p.g, &p.b}) {
      changed = changed || double(float(*c)) != *c;
      *c = double(float(*c));
    }
  ASSERT_TRUE(changed);
  const std::string rewritten = dir_ / "rewritten.exr";
  writeFilmExr(rewritten, f.film, f.metadata, 1.0);
  // Keep the original's checksum attribute, as a tool copying unknown attributes would.
  std::string bytes = readFile(rewritten);
  auto checksumOf = [](const std::string& b) {
    const std::string key = std::string("mltfarm.sumsSha256") + '\0' + "string" + '\0';
    const size_t at = b.find(key);
    return at == std::string::npos ? std::string::npos : at + key.size() + 4;
  };
  ASSERT_NE(checksumOf(bytes), std::string::npos);
  bytes.replace(checksumOf(bytes), 64, original.substr(checksumOf(original), 64));
  writeBytes(rewritten, bytes);
  std::vector<std::string> parts = parts_;
  parts[0] = rewritten;
  std::string e = errorOf([&] { mergePartialExrs(parts, dir_ / "o.exr", ""); });
  EXPECT_NE(e.find("do not match their checksum"), std::string::npos) << e;
  // A tool that dropped the attribute (here: renamed it) leaves a partial without a checksum: refused too.
  const size_t name = bytes.find("mltfarm.sumsSha256");
  ASSERT_NE(name, std::string::npos);
  bytes.replace(name, 18, "mltfarm.sumsSHA256");
  writeBytes(rewritten, bytes);
  e = errorOf([&] { mergePartialExrs(parts, dir_ / "o.exr", ""); });
  EXPECT_NE(e.find("no checksum of the raw sums"), std::string::npos) << e;
}

TEST_F(MergeGuard, TheOutputMayNotBeAnInput) {
  const std::string before = readFile(parts_[1]);
  std::string e = errorOf([&] { mergePartialExrs(parts_, parts_[1], ""); });
  EXPECT_NE(e.find("is one of the inputs"), std::string::npos) << e;
  // Another name of the same file.
  fs::create_symlink(parts_[1], dir_ / "alias.exr");
  e = errorOf([&] { mergePartialExrs(parts_, dir_ / "alias.exr", ""); });
  EXPECT_NE(e.find("is one of the inputs"), std::string::npos) << e;
  e = errorOf([&] { mergePartialExrs(parts_, dir_ / "o.exr", parts_[0]); });
  EXPECT_NE(e.find("is one of the inputs"), std::string::npos) << e;
  EXPECT_EQ(readFile(parts_[1]), before);
}

// A FIFO is refused by its type. The test holds it open for reading and writing with bytes in it, so
// that a reader that opens it anyway gets those bytes instead of blocking.
TEST_F(MergeGuard, AFifoIsRefusedNotRead) {
  const std::string fifo = dir_ / "fifo.exr";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const int fd = open(fifo.c_str(), O_RDWR | O_NONBLOCK);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(write(fd, "garbage!", 8), 8);
  std::vector<std::string> parts = parts_;
  parts.push_back(fifo);
  const std::string e = errorOf([&] { mergePartialExrs(parts, dir_ / "o.exr", ""); });
  close(fd);
  EXPECT_NE(e.find("not a regular file"), std::string::npos) << e;
}

}  // namespace
}  // namespace mlt::farm::test
