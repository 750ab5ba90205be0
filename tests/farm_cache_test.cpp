// The worker's bounded caches: the eviction policy (LRU order, entries in use pinned, bytes counted), the
// value cache built on it, the scene cache's bundles on disk (deleted when evicted, fetched again when
// needed), and a worker with a tiny cache rendering jobs on different scenes one after the other.
#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <thread>

#include "common/farm/bundle.h"
#include "common/farm/lru_budget.h"
#include "common/farm/lru_map.h"
#include "common/farm/scene_cache.h"
#include "common/io/exr_io.h"
#include "tests/farm/farm_harness.h"
#include "tests/support/temp_dir.h"

namespace mlt::farm::test {
namespace {

TEST(LruBudget, EvictsLeastRecentlyUsedFirstUntilTheTotalFits) {
  LruBudget b(100);
  b.put("a", 40);
  b.put("b", 40);
  b.put("c", 20);
  EXPECT_EQ(b.bytes(), 100u);
  EXPECT_TRUE(b.evict().keys.empty());  // exactly at the bound: nothing goes
  EXPECT_TRUE(b.touch("a"));            // now b is the least recently used
  EXPECT_FALSE(b.touch("zz"));
  EXPECT_EQ(b.order(), (std::vector<std::string>{"b", "c", "a"}));
  b.put("d", 30);  // 130
  LruBudget::Evicted ev = b.evict();
  EXPECT_EQ(ev.keys, (std::vector<std::string>{"b"}));  // 90 fits: c stays
  EXPECT_FALSE(ev.overBound);
  EXPECT_EQ(b.bytes(), 90u);
  EXPECT_FALSE(b.contains("b"));
  b.put("c", 70);  // resized and used: 40 + 70 + 30
  EXPECT_EQ(b.bytes(), 140u);
  EXPECT_EQ(b.evict().keys, (std::vector<std::string>{"a"}));
  EXPECT_EQ(b.bytes(), 100u);
  b.erase("d");
  EXPECT_EQ(b.bytes(), 70u);
  EXPECT_EQ(b.size(), 1u);
}

TEST(LruBudget, PinnedEntriesAreNeverEvictedAndTheOverrunIsReportedOnce) {
  LruBudget b(10);
  b.put("old", 8);
  b.put("new", 8);
  b.pin("old");
  b.pin("old");  // two tasks
  LruBudget::Evicted ev = b.evict();
  EXPECT_EQ(ev.keys, (std::vector<std::string>{"new"}));  // the older one is in use
  EXPECT_TRUE(b.contains("old"));
  b.put("big", 50);
  b.pin("big");
  ev = b.evict();
  EXPECT_TRUE(ev.keys.empty());
  EXPECT_TRUE(ev.overBound);
  EXPECT_TRUE(ev.newlyOverBound);
  EXPECT_EQ(b.bytes(), 58u);  // over the bound for the while
  ev = b.evict();
  EXPECT_TRUE(ev.overBound);
  EXPECT_FALSE(ev.newlyOverBound);  // said once
  b.unpin("big");
  EXPECT_EQ(b.evict().keys, (std::vector<std::string>{"big"}));
  b.unpin("old");
  EXPECT_TRUE(b.pinned("old"));
  b.unpin("old");
  EXPECT_FALSE(b.pinned("old"));
  EXPECT_THROW(b.unpin("old"), std::logic_error);
  EXPECT_THROW(LruBudget(0), std::invalid_argument);
}

using IntMap = LruMap<int>;
std::pair<IntMap::Value, uint64_t> made(int v, uint64_t bytes, int* calls) {
  ++*calls;
  return {std::make_shared<const int>(v), bytes};
}

TEST(LruMap, AValueInUseStaysAndIsMadeAgainAfterEviction) {
  IntMap m("test", 100);
  int calls = 0;
  IntMap::Value a = m.get("a", [&] { return made(1, 60, &calls); });
  EXPECT_EQ(*m.get("a", [&] { return made(99, 60, &calls); }), 1);  // cached: not made again
  EXPECT_EQ(calls, 1);
  IntMap::Value b = m.get("b", [&] { return made(2, 60, &calls); });  // 120 > 100, both in use
  EXPECT_TRUE(m.contains("a"));
  EXPECT_TRUE(m.contains("b"));
  EXPECT_EQ(m.bytes(), 120u);
  a.reset();  // released: the least recently used and over the bound, so it goes now
  EXPECT_FALSE(m.contains("a"));
  EXPECT_EQ(m.bytes(), 60u);
  EXPECT_EQ(*b, 2);  // the one in use is intact
  EXPECT_EQ(*m.get("a", [&] { return made(3, 60, &calls); }), 3);  // made again
  EXPECT_EQ(calls, 3);
}

TEST(LruMap, FailedMakeLeavesNothingAndConcurrentGetsMakeOnce) {
  IntMap m("test", 1000);
  EXPECT_THROW(m.get("x", []() -> std::pair<IntMap::Value, uint64_t> { throw std::runtime_error("no"); }),
               std::runtime_error);
  EXPECT_FALSE(m.contains("x"));
  EXPECT_EQ(m.size(), 0u);
  std::atomic<int> calls{0};
  std::vector<std::thread> threads;
  std::vector<int> got(8, 0);
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&, t] {
      got[t] = *m.get("x", [&] {
        ++calls;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        return std::pair{std::make_shared<const int>(7), uint64_t(1)};
      });
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(calls.load(), 1);
  for (int v : got) EXPECT_EQ(v, 7);
}

// A one-triangle scene in a bundle; `tag` makes the bytes (and the hash) differ.
const char* kScene =
    "<scene version=\"3.0.0\">\n"
    "  <sensor type=\"perspective\">\n"
    "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" value=\"16\"/></film>\n"
    "  </sensor>\n"
    "  <shape type=\"obj\"><string name=\"filename\" value=\"tri.obj\"/>\n"
    "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"1, 1, 1\"/></emitter></shape>\n"
    "</scene>\n";
std::vector<BundleFile> triangleBundle(const std::string& tag) {
  return {{"scene.xml", kScene}, {"tri.obj", "# " + tag + "\nv -1 -1 3\nv 1 -1 3\nv 0 1 3\nf 1 2 3\n"}};
}
uint64_t bundleBytes(const std::vector<BundleFile>& files) {
  uint64_t n = 0;
  for (const BundleFile& f : files) n += f.data.size();
  return n;
}

TEST(SceneCacheEviction, BundlesOutOfUseAreDeletedFromDiskAndFetchedAgain) {
  mlt::TempDir dir("scene_evict");
  const std::string cacheDir = (dir.path() / "cache").string();
  const auto a = triangleBundle("a"), b = triangleBundle("b");
  const std::string ha = bundleHash(a), hb = bundleHash(b);
  std::map<std::string, int> fetches;
  auto fetch = [&](const std::string& hash) {
    ++fetches[hash];
    return hash == ha ? a : b;
  };
  {  // Roomy: everything stays, the bytes are the bundles' plus the scenes' estimates.
    SceneCache roomy(cacheDir, fetch);
    auto sa = roomy.get(ha, "scene.xml", {}, 16, 16);
    auto sb = roomy.get(hb, "scene.xml", {}, 16, 16);
    const uint64_t sceneBytes = estimateSceneBytes(sa->desc());
    EXPECT_GT(sceneBytes, 3 * (3 * sizeof(Vec3) + 3 * sizeof(uint32_t)) - 1);
    EXPECT_EQ(roomy.bytes(), bundleBytes(a) + bundleBytes(b) + 2 * sceneBytes);
    EXPECT_TRUE(fs::exists(fs::path(cacheDir) / ha));
  }
  // A new cache on the same directory counts the bundles found there (no fetch).
  const uint64_t oneBundle = bundleBytes(a);
  {
    SceneCache again(cacheDir, fetch);
    EXPECT_TRUE(again.hasBundle(ha));
    EXPECT_TRUE(again.hasBundle(hb));
    EXPECT_EQ(again.bytes(), 2 * oneBundle);
  }
  // Tiny: a bundle or a scene no task holds goes as soon as something else comes in.
  SceneCache tiny(cacheDir, fetch, 1);
  EXPECT_FALSE(tiny.hasBundle(ha));  // the found bundles did not fit: deleted
  EXPECT_FALSE(fs::exists(fs::path(cacheDir) / ha));
  EXPECT_FALSE(fs::exists(fs::path(cacheDir) / hb));
  EXPECT_EQ(tiny.bytes(), 0u);
  auto sa = tiny.get(ha, "scene.xml", {}, 16, 16);  // in use: stays, over the bound
  EXPECT_EQ(fetches[ha], 2);
  EXPECT_FALSE(fs::exists(fs::path(cacheDir) / ha));  // the bundle, no longer needed once built, went
  EXPECT_EQ(tiny.bytes(), estimateSceneBytes(sa->desc()));
  auto sa2 = tiny.get(ha, "scene.xml", {}, 16, 16);  // the same built scene, no fetch
  EXPECT_EQ(sa.get(), sa2.get());
  EXPECT_EQ(fetches[ha], 2);
  sa.reset();
  sa2.reset();  // out of use: evicted
  EXPECT_EQ(tiny.bytes(), 0u);
  auto sb = tiny.get(hb, "scene.xml", {}, 16, 16);
  auto sa3 = tiny.get(ha, "scene.xml", {}, 16, 16);  // fetched again after eviction, and it works
  EXPECT_EQ(fetches[ha], 3);
  EXPECT_EQ(sa3->desc().meshes.size(), 1u);
  EXPECT_EQ(sb->desc().meshes.size(), 1u);
  // Nothing but the cache's own entries is left on disk (no temporary or evicted leftovers).
  size_t left = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(cacheDir)) ++left;
  EXPECT_EQ(left, 0u);
}

// A worker whose cache holds less than one scene renders jobs on two scenes one after the other; the
// first scene, evicted by the second, is fetched again for a third job whose image is the first's.
TEST(FarmCache, WorkerWithATinyCacheRendersEveryJobRight) {
  Farm farm;
  farm.startCoordinator();
  farm.startWorker(1, {"--cache-max-mb", "0.001", "--plan-cache-max-mb", "0.001"});
  auto c = farm.client();
  const std::string spheres = std::string(MLTFARM_SOURCE_DIR) + "/scenes/cornell-spheres.xml";
  std::vector<std::string> exrs, hashes;
  for (const std::string& scene : {cornellBox(), spheres, cornellBox()}) {
    JobStatus s = c.submit(scene, tinySettings("pssmlt"));
    hashes.push_back(s.sceneHash.substr(0, 12));
    ASSERT_EQ(farm.waitDone(s.jobId).state, JobState::Done) << scene;
    exrs.push_back(farm.dir / (s.jobId + ".exr"));
    c.fetch(s.jobId, exrs.back());
  }
  const ExrImage first = readExr(exrs[0]), other = readExr(exrs[1]), again = readExr(exrs[2]);
  ASSERT_EQ(first.rgb.size(), again.rgb.size());
  EXPECT_EQ(std::memcmp(first.rgb.data(), again.rgb.data(), first.rgb.size() * sizeof(Color)), 0)
      << "the scene fetched again after eviction renders other pixels";
  ASSERT_EQ(first.rgb.size(), other.rgb.size());
  EXPECT_NE(std::memcmp(first.rgb.data(), other.rgb.data(), first.rgb.size() * sizeof(Color)), 0);
  const std::string log = readFile(farm.dir / "worker-0.log");
  // The box's bundle (larger than the whole cache) was evicted once out of use, so the third job fetched it
  // again; how often within a job depends on whether a task still held it when the next one started.
  ASSERT_EQ(hashes[0], hashes[2]);
  EXPECT_GE(countOccurrences(log, "event=scene_cached scene_hash=" + hashes[0]), 2u) << log;
  EXPECT_GE(countOccurrences(log, "event=scene_cached scene_hash=" + hashes[1]), 1u) << log;
  EXPECT_GE(countOccurrences(log, "event=cache_evicted cache=scenes"), 3u) << log;
  EXPECT_GE(countOccurrences(log, "event=cache_evicted cache=plans"), 2u) << log;
}

TEST(FarmCache, WorkerRefusesACacheBoundOfZero) {
  for (const char* flag : {"--cache-max-mb", "--plan-cache-max-mb"}) {
    TempDir dir;
    ChildProcess p({toolsDir() + "/mltfarm-worker", "--coordinator", "127.0.0.1:1", flag, "0"}, dir / "worker.log",
                   false);
    EXPECT_EQ(p.wait(std::chrono::seconds(30)), 105) << flag;  // CLI11's validation error
    EXPECT_NE(readFile(dir / "worker.log").find("greater than 0"), std::string::npos) << readFile(dir / "worker.log");
  }
}

}  // namespace
}  // namespace mlt::farm::test
