// The pieces of the farm layer that keep the farm cheap without changing a bit: the zero-run film
// encoding of uploads (exact, and smaller for the sparse films tasks produce), the coordinator's result
// files (exact round trip; a torn file is refused, never half-read) and the task split (small films keep
// 64 tasks, a 256x256 Markov chain job gets fewer, each task a contiguous range covering every unit).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>

#include "common/farm/tasks.h"
#include "common/film/sparse_splats.h"
#include "coordinator/result_store.h"
#include "proto/convert.h"
#include "proto/sparse_film.h"

namespace mlt::farm {
namespace {

namespace fs = std::filesystem;

// A film with a fraction `density` of nonzero words in every buffer (including a zero splat layer 0
// next to a used layer 3, as an mmlt task has), values of all magnitudes and signs, and a -0.0.
Film randomFilm(int w, int h, double density, uint32_t seed) {
  Film f(w, h);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  auto value = [&] { return u(rng) < density ? std::ldexp(u(rng) - 0.5, int(rng() % 60) - 30) : 0.0; };
  for (auto& p : f.pixelSums()) p = RGBd{value(), value(), value()};
  for (auto& c : f.pixelCounts()) c = value();
  for (auto& p : f.splatLayer(3)) p = RGBd{value(), value(), value()};
  f.pixelCounts()[0] = -0.0;  // not a zero word (its sign bit is set): it must come back as -0.0
  f.setNonFiniteSamples(7);
  return f;
}

bool sameBits(const Film& a, const Film& b) {
  if (a.width() != b.width() || a.height() != b.height() || a.splatLayers() != b.splatLayers() ||
      a.nonFiniteSamples() != b.nonFiniteSamples())
    return false;
  auto same = [](const auto& x, const auto& y) {
    return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0;
  };
  if (!same(a.pixelSums(), b.pixelSums()) || !same(a.pixelCounts(), b.pixelCounts())) return false;
  for (uint32_t l : a.splatLayers())
    if (!same(a.splatLayer(l), b.splatLayer(l))) return false;
  return true;
}

TEST(FarmLayer, ZeroRunFilmsRoundTripBitExactly) {
  for (double density : {0.0, 0.001, 0.3, 0.9, 1.0}) {
    const Film f = randomFilm(37, 23, density, uint32_t(density * 1000) + 1);
    const std::string bytes = wire::encodeFilmZeroRuns(f);
    EXPECT_LE(bytes.size(), wire::maxZeroRunsBytes(37, 23, f.splatLayers().size())) << density;
    const Film g = wire::decodeFilmZeroRuns(37, 23, bytes, 7, f.splatLayers());
    EXPECT_TRUE(sameBits(f, g)) << "density " << density;
    if (density <= 0.3) EXPECT_LT(bytes.size(), wire::encodeFilm(f).size() / 2) << density;
  }
}

// The decoder writes the literal words through writeRange: the blocks only zero runs cover stay unmarked
// (pixel_buffer.h), so the coordinator's merge and develop never read them.
TEST(FarmLayer, ZeroRunDecodeMarksOnlyTheBlocksItFills) {
  Film f(1000, 8);  // 8000 pixels: pixel i is in block i / kBlock
  f.addSplat({10.5f, 0.5f}, Color(1, 2, 3), 3);   // pixel 10
  f.addSplat({500.5f, 2.5f}, Color(0, 0, 4), 3);  // pixel 2500
  f.addSplat({999.5f, 7.5f}, Color(5, 0, 0), 0);  // the last pixel, 7999
  // The encoder counts unwritten blocks as zeros without reading them: the same stream as with every
  // block marked (data() marks them all).
  Film marked = f;
  marked.pixelSums().data();
  for (uint32_t l : marked.splatLayers()) marked.splatLayer(l).data();
  EXPECT_EQ(wire::encodeFilmZeroRuns(marked), wire::encodeFilmZeroRuns(f));
  const Film g = wire::decodeFilmZeroRuns(1000, 8, wire::encodeFilmZeroRuns(f), 0, f.splatLayers());
  EXPECT_TRUE(sameBits(f, g));
  std::vector<size_t> l3, l0, pixels;
  g.splatLayer(3).forEachWrittenBlock([&](size_t b, const RGBd*, size_t) { l3.push_back(b); });
  g.splatLayer(0).forEachWrittenBlock([&](size_t b, const RGBd*, size_t) { l0.push_back(b); });
  g.pixelSums().forEachWrittenBlock([&](size_t b, const RGBd*, size_t) { pixels.push_back(b); });
  EXPECT_EQ(l3, (std::vector<size_t>{10 / PixelBuffer::kBlock, 2500 / PixelBuffer::kBlock}));
  EXPECT_EQ(l0, (std::vector<size_t>{7999 / PixelBuffer::kBlock}));
  EXPECT_TRUE(pixels.empty());
  const std::vector<double> scales = {0.5, 0, 0, 2};
  const std::vector<Color> a = f.develop(scales), b = g.develop(scales);
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(Color)), 0);
}

TEST(FarmLayer, MalformedZeroRunStreamsAreRefused) {
  const Film f = randomFilm(8, 8, 0.5, 3);
  const std::string good = wire::encodeFilmZeroRuns(f);
  const std::vector<uint32_t> layers = f.splatLayers();
  EXPECT_THROW(wire::decodeFilmZeroRuns(8, 8, good.substr(0, good.size() - 3), 0, layers), wire::WireError);
  EXPECT_THROW(wire::decodeFilmZeroRuns(8, 8, good + good, 0, layers), wire::WireError);
  EXPECT_THROW(wire::decodeFilmZeroRuns(8, 8, std::string("\x01\x00", 2), 0, layers), wire::WireError);  // too short
  EXPECT_THROW(wire::decodeFilmZeroRuns(9, 8, good, 0, layers), wire::WireError);  // another film size
}

PartialResult somePartial() {
  PartialResult r;
  r.film = randomFilm(16, 12, 0.2, 11);
  r.samples = 12345;
  r.units = {4, 5, 6};
  r.seconds = 1.5;
  r.stats.proposedPerKind = {10, 20};
  r.stats.acceptedPerKind = {3, 9};
  r.stats.secondsPerKind = {0.125, 0.75};  // wall time per move kind (issue 12)
  return r;
}

TEST(FarmLayer, ResultFilesRoundTripAndTornFilesAreRefused) {
  const fs::path dir = fs::temp_directory_path() / ("mltfarm-results-" + std::to_string(getpid()));
  fs::remove_all(dir);
  ResultStore store(dir.string());
  const PartialResult r = somePartial();
  store.put(3, 7, r);
  store.put(3, 2, r);
  store.put(3, 2, r);  // a duplicate upload writes the same bytes again
  EXPECT_EQ(store.stored(3), (std::vector<uint32_t>{2, 7}));
  EXPECT_TRUE(store.stored(4).empty());
  std::optional<PartialResult> back = store.load(3, 7);
  ASSERT_TRUE(back);
  EXPECT_TRUE(sameBits(back->film, r.film));
  EXPECT_EQ(back->samples, r.samples);
  EXPECT_EQ(back->units, r.units);
  EXPECT_EQ(back->stats.acceptedPerKind, r.stats.acceptedPerKind);
  EXPECT_EQ(back->stats.secondsPerKind, r.stats.secondsPerKind);
  std::string why;
  EXPECT_FALSE(store.load(3, 5, &why));
  EXPECT_EQ(why, "missing");
  // A power loss may leave a renamed file with zeroed pages: it must not parse as a result.
  const fs::path file = dir / "job-3" / "results" / "task-000007.part";
  const auto size = fs::file_size(file);
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(std::streamoff(size / 2));
    const std::string zeros(64, '\0');
    f.write(zeros.data(), std::streamsize(zeros.size()));
  }
  EXPECT_FALSE(store.load(3, 7, &why));
  EXPECT_NE(why.find("checksum"), std::string::npos) << why;
  fs::resize_file(dir / "job-3" / "results" / "task-000002.part", size / 3);
  EXPECT_FALSE(store.load(3, 2, &why));
  fs::remove_all(dir);
}

JobPlan chainPlan(int width, int height, uint32_t chains, uint64_t mutationsPerChain) {
  JobPlan plan;
  plan.settings.method = "mmlt";
  plan.settings.width = width;
  plan.settings.height = height;
  for (uint32_t i = 0; i < chains; ++i) {
    WorkUnit u;
    u.index = i;
    u.mutations = mutationsPerChain;
    plan.units.push_back(u);
  }
  return plan;
}

void expectContiguous(const std::vector<TaskRange>& tasks, uint32_t units) {
  ASSERT_FALSE(tasks.empty());
  EXPECT_EQ(tasks.front().begin, 0u);
  EXPECT_EQ(tasks.back().end, units);
  for (size_t t = 0; t < tasks.size(); ++t) {
    EXPECT_LT(tasks[t].begin, tasks[t].end);
    if (t > 0) {
      EXPECT_EQ(tasks[t].begin, tasks[t - 1].end);
    }
  }
}

// The wall time per move kind travels with the partial header; a negative or non-finite one is refused.
TEST(FarmLayer, MoveSecondsTravelWithThePartialAndBadOnesAreRefused) {
  PartialResult r = somePartial();
  r.stats.largeStepLuminanceSums.assign(2, TargetSums{});  // a relative target's (develop.h (D8))
  r.stats.largeStepLuminanceSums[1].add(0.75, 0.5);
  const PartialResult back = wire::partialFromHeaderBytes(wire::partialHeaderBytes(r), r.film);
  EXPECT_EQ(back.stats.secondsPerKind, r.stats.secondsPerKind);
  EXPECT_EQ(back.stats.largeStepLuminanceSums, r.stats.largeStepLuminanceSums);
  for (double bad : {-1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    r.stats.secondsPerKind = {0.5, bad};
    try {
      wire::partialFromHeaderBytes(wire::partialHeaderBytes(r), r.film);
      ADD_FAILURE() << "seconds " << bad << " accepted";
    } catch (const wire::WireError& e) {
      EXPECT_NE(std::string(e.what()).find("seconds_per_kind"), std::string::npos) << e.what();
    }
  }
}

// A unit's sparse splats (common/film/sparse_splats.h) never travel: only merged results, whose splats are
// in their film, go on the wire; one still holding splats is refused instead of sent without them.
TEST(FarmLayer, AResultWithPendingSparseSplatsIsNotSent) {
  PartialResult r = somePartial();
  SparseSplatter splatter(r.film.width(), r.film.height(), 1);
  splatter.addSplat({0.5f, 0.5f}, Color(1));
  r.splats = splatter.take();
  EXPECT_THROW(wire::partialHeaderBytes(r), std::logic_error);
  r.foldSplats();
  EXPECT_NO_THROW(wire::partialHeaderBytes(r));
}

TEST(FarmLayer, TasksAreBoundedByTheirFilmTraffic) {
  // The tests' jobs: 32x32 films cost nothing to move, 96 units make 64 tasks.
  const JobPlan tiny = chainPlan(32, 32, 96, 8 * 1024 / 96);
  expectContiguous(splitTasks(tiny), 96);
  EXPECT_EQ(splitTasks(tiny).size(), 64u);
  // The README's default job: 256x256, 1024 chains, 256 mutations per pixel. With one splat layer (a
  // film of 3.7 MB) the traffic bound, max(64 MiB, 4 B x 16.8 M mutations) = 67 MB, allows 18 films.
  JobPlan def = chainPlan(256, 256, 1024, 256 * 256 * 256 / 1024);
  expectContiguous(splitTasks(def), 1024);
  EXPECT_EQ(findMethod("mmlt").filmLayers(def), 1u);
  EXPECT_EQ(splitTasks(def).size(), 18u);
  // But mmlt's films hold a chain layer and a strata layer per path length (5 lengths: 11 layers,
  // 19 MB): 3 such films fit, and the floor gives kMinTasks.
  def.norm.mutationsPerLength = {0, 1, 1, 1, 1, 1};
  EXPECT_EQ(findMethod("mmlt").filmLayers(def), 11u);
  EXPECT_EQ(splitTasks(def).size(), kMinTasks);
  // A sampling method's film has one layer whatever the plan says.
  EXPECT_EQ(findMethod("bdpt").filmLayers(def), 1u);
  // Four times the work: four times the films (still at most 64).
  const JobPlan longer = chainPlan(256, 256, 1024, 4 * 256 * 256 * 256 / 1024);
  EXPECT_EQ(splitTasks(longer).size(), 64u);
  // Little work on a large film: kMinTasks while 512 MiB holds that many films (1280x720: 10 of 52 MB),
  // fewer where it does not (1920x1080: 4 of 116 MB), but never fewer than min(units, 4).
  EXPECT_EQ(splitTasks(chainPlan(1280, 720, 100, 10)).size(), kMinTasks);
  EXPECT_EQ(splitTasks(chainPlan(1920, 1080, 100, 10)).size(), 4u);
  JobPlan hd = chainPlan(1280, 720, 100, 10);
  hd.norm.mutationsPerLength = {0, 1, 1, 1, 1, 1};  // 273 MB films
  EXPECT_EQ(splitTasks(hd).size(), 4u);
  EXPECT_EQ(splitTasks(chainPlan(1920, 1080, 3, 10)).size(), 3u);
}

// The direct-light pilot's numbers travel with the plan: a share with its CV, and a share whose CV the
// pilot never drew (a share below the rule's threshold decides alone, direct_light_rule.h) stays
// unmeasured, as -1, instead of failing the plan's check (a farm job on caustic-mirror or door-ajar did);
// a CV on the wire that is negative or not finite is still refused.
TEST(FarmLayer, ThePilotsShareAndAnUnmeasuredCvTravelWithThePlan) {
  JobPlan plan = chainPlan(8, 8, 4, 16);
  plan.settings.mutationsPerPixel = 1;
  for (const double cv : {0.52, -1.0}) {
    plan.norm.directShare = 0.14;
    plan.norm.directCv = cv;
    const JobPlan back = wire::parseJobPlan(wire::jobPlanBytes(plan));
    EXPECT_EQ(back.norm.directShare, 0.14);
    EXPECT_EQ(back.norm.directCv, cv);
  }
  plan.norm.directShare = -1;  // no pilot: neither number is sent
  EXPECT_FALSE(wire::toProto(plan).norm().has_direct_share());
  EXPECT_FALSE(wire::toProto(plan).norm().has_direct_cv());
  for (const double bad : {-1.0, std::numeric_limits<double>::infinity()}) {
    v1::JobPlan p = wire::toProto(plan);
    p.mutable_norm()->set_direct_share(0.5);
    p.mutable_norm()->set_direct_cv(bad);
    EXPECT_THROW(wire::fromProto(p), std::exception) << bad;
  }
}

// The relative target's importance map travels with the plan bit for bit (every chain's target reads it),
// and a map that does not fit the plan's film or holds a value that is not a positive finite number is
// refused, naming the field.
TEST(FarmLayer, TheImportanceMapTravelsWithThePlanAndABadOneIsRefused) {
  JobPlan plan = chainPlan(8, 6, 4, 16);
  plan.settings.mutationsPerPixel = 1;
  EXPECT_FALSE(wire::toProto(plan).norm().has_importance());  // no map: nothing sent
  std::vector<double> sums(48);
  for (size_t i = 0; i < sums.size(); ++i) sums[i] = 0.25 * double(i % 7);
  plan.norm.importance = importanceFromTileSums(8, 6, sums, std::vector<uint64_t>(48, 1), 0.5);
  ASSERT_FALSE(plan.norm.importance.empty());
  const JobPlan back = wire::parseJobPlan(wire::jobPlanBytes(plan));
  EXPECT_EQ(back.norm.importance, plan.norm.importance);
  const auto refused = [&](const std::function<void(v1::ImportanceMap&)>& edit, const char* what) {
    v1::JobPlan p = wire::toProto(plan);
    edit(*p.mutable_norm()->mutable_importance());
    try {
      wire::fromProto(p);
      ADD_FAILURE() << what << ": accepted";
    } catch (const wire::WireError& e) {
      EXPECT_EQ(e.field(), "plan.norm.importance") << what;
    }
  };
  refused([](v1::ImportanceMap& m) { m.set_h(3, std::numeric_limits<float>::quiet_NaN()); }, "NaN");
  refused([](v1::ImportanceMap& m) { m.set_h(0, 0.0f); }, "zero");
  refused([](v1::ImportanceMap& m) { m.mutable_h()->RemoveLast(); }, "a value short");
  refused([](v1::ImportanceMap& m) { m.set_tile_size(2); }, "another tile size");
  refused([](v1::ImportanceMap& m) { m.set_film_width(16); }, "another film");
  // b_lum's estimates (develop.h (D8)) travel too, and never without a map.
  plan.norm.bootstrapLuminance.assign(2, BootstrapEstimate{});
  plan.norm.bootstrapLuminance[1] = {4096, 0.25, 0.001, 0.3, 2.5, 0.24, 0.001, 0.2, 0.01};
  EXPECT_EQ(wire::parseJobPlan(wire::jobPlanBytes(plan)).norm.bootstrapLuminance, plan.norm.bootstrapLuminance);
  v1::JobPlan noMap = wire::toProto(plan);
  noMap.mutable_norm()->clear_importance();
  try {
    wire::fromProto(noMap);
    ADD_FAILURE() << "a luminance estimate without a map was accepted";
  } catch (const wire::WireError& e) {
    EXPECT_EQ(e.field(), "plan.norm.bootstrap_luminance");
  }
}

// A tempered target's power (common/mlt/target.h (T1)) travels with the plan (absent: 1), and with it b_lum's
// estimates without a map; a power outside (0, 1] is refused, naming the field.
TEST(FarmLayer, TheTargetPowerTravelsWithThePlanAndABadOneIsRefused) {
  JobPlan plan = chainPlan(8, 6, 4, 16);
  EXPECT_FALSE(wire::toProto(plan).norm().has_target_power());  // 1: nothing sent
  EXPECT_EQ(wire::parseJobPlan(wire::jobPlanBytes(plan)).norm.targetPower, 1.0);
  plan.norm.targetPower = 0.65;
  plan.norm.bootstrapLuminance.assign(2, BootstrapEstimate{});
  plan.norm.bootstrapLuminance[1] = {4096, 0.25, 0.001, 0.3, 2.5, 0.24, 0.001, 0.2, 0.01};
  const JobPlan back = wire::parseJobPlan(wire::jobPlanBytes(plan));
  EXPECT_EQ(back.norm.targetPower, 0.65);
  EXPECT_TRUE(back.norm.importance.empty());
  EXPECT_EQ(back.norm.bootstrapLuminance, plan.norm.bootstrapLuminance);
  for (const double bad : {0.0, -0.5, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
    v1::JobPlan p = wire::toProto(plan);
    p.mutable_norm()->set_target_power(bad);
    try {
      wire::fromProto(p);
      ADD_FAILURE() << bad << ": accepted";
    } catch (const wire::WireError& e) {
      EXPECT_EQ(e.field(), "plan.norm.target_power") << bad;
    }
  }
  v1::JobPlan plain = wire::toProto(plan);
  plain.mutable_norm()->clear_target_power();  // power 1 and no map: b_lum's estimates do not belong
  try {
    wire::fromProto(plain);
    ADD_FAILURE() << "a luminance estimate without a map or a power was accepted";
  } catch (const wire::WireError& e) {
    EXPECT_EQ(e.field(), "plan.norm.bootstrap_luminance");
  }
}

// The count of candidates b is developed from (Normalization::bootstrapSamplesInB, bootstrap.h fixedCount)
// travels with the plan; a plan without it (from before it) holds every candidate; more than the bootstrap
// drew is refused, naming the field.
TEST(FarmLayer, TheCandidatesInBTravelWithThePlanAndTooManyAreRefused) {
  JobPlan plan = chainPlan(8, 6, 4, 16);
  plan.norm.bootstrapSamples = 4096;
  plan.norm.bootstrapSamplesInB = 1024;
  EXPECT_EQ(wire::parseJobPlan(wire::jobPlanBytes(plan)).norm.bootstrapSamplesInB, 1024u);
  v1::JobPlan old = wire::toProto(plan);
  old.mutable_norm()->clear_bootstrap_samples_in_b();
  EXPECT_EQ(wire::fromProto(old).norm.bootstrapSamplesInB, 4096u);
  v1::JobPlan bad = wire::toProto(plan);
  bad.mutable_norm()->set_bootstrap_samples_in_b(4097);
  try {
    wire::fromProto(bad);
    ADD_FAILURE() << "more candidates in b than the bootstrap drew were accepted";
  } catch (const wire::WireError& e) {
    EXPECT_EQ(e.field(), "plan.norm.bootstrap_samples_in_b");
  }
}

}  // namespace
}  // namespace mlt::farm
