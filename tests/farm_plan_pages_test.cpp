// Plans with many units are fetched in pages (issue 13, "Limits and clean-up"). A plan holds one work unit
// per chain or sample batch; with up to 2^20 of them its encoding passes gRPC's 4 MiB receive limit, and a
// worker that fetched it in one reply could never run the job. FetchPlan answers a page of units
// [first_unit, first_unit + n), n capped by the server (proto/plan_pages.h); the worker fetches pages
// until it holds every unit and checks that they all belong to the same plan.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "common/io/exr_io.h"
#include "proto/plan_pages.h"
#include "worker/uploader.h"
#include "proto/convert.h"
#include "tests/farm/farm_harness.h"
#include "tests/farm/in_process_farm.h"

namespace mlt::farm::test {
namespace {

constexpr size_t kGrpcDefaultLimit = 4u << 20;

// pt on a 1x1 film with one sample per unit: 200000 units, about 5 MB encoded.
const char* kManyUnits = "--method pt --seed 3 --width 1 --height 1 --spp 200000 --samples-per-unit 1 --max-depth 3";

TEST(FarmPlanPages, APlanLargerThanTheReceiveLimitIsFetchedByTheWorkersAndRendersTheInProcessPixels) {
  const cli::CommandLineSettings cl = parseRenderSettings(kManyUnits);
  const cli::LocalRenderResult local = renderInProcess(cornellBox(), cl);
  ASSERT_EQ(local.plan.units.size(), 200000u);
  const size_t encoded = wire::toProto(local.plan).ByteSizeLong();
  ASSERT_GT(encoded, kGrpcDefaultLimit) << "the plan must not fit one reply for this test to mean anything";

  WorkerOptions wo;
  wo.threads = 1;
  InProcessFarm farm(2, wo);
  const ExrImage image = readExr(farm.render(cornellBox(), cl, "pages.exr"));
  farm.stop();
  uint64_t planBytes = 0;
  for (int i = 0; i < 2; ++i) planBytes += uint64_t(farm.worker(size_t(i)).metrics().downloadBytes.Value());
  EXPECT_GE(planBytes, encoded) << "no worker received the whole plan";
  ASSERT_EQ(image.rgb.size(), local.image.size());
  EXPECT_EQ(std::memcmp(image.rgb.data(), local.image.data(), local.image.size() * sizeof(Color)), 0)
      << "the farm's pixels differ from the in-process render's";
  EXPECT_GT(image.rgb[0].r + image.rgb[0].g + image.rgb[0].b, 0.0f);
}

// A job of 40000 units on a coordinator without workers: its plan stays put while pages are fetched raw.
struct PlannedJob {
  InProcessFarm farm{0};
  std::string jobId;
  JobPlan expected;
  std::unique_ptr<v1::WorkerService::Stub> stub;
  PlannedJob() {
    const cli::CommandLineSettings cl =
        parseRenderSettings("--method pt --seed 3 --width 1 --height 1 --spp 40000 --samples-per-unit 1");
    FarmClient client(farm.channel());
    jobId = client.submit(cornellBox(), cli::submittedSettings(cl)).jobId;
    JobStatus st = client.get(jobId);
    for (int i = 0; i < 3000 && (st.state == JobState::Queued || st.state == JobState::Planning); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      st = client.get(jobId);
    }
    EXPECT_EQ(st.state, JobState::Running) << describeStatus(st);
    stub = v1::WorkerService::NewStub(makeChannel(farm.channel()));
  }
  grpc::Status fetch(uint32_t firstUnit, uint32_t maxUnits, v1::JobPlan& page) {
    grpc::ClientContext ctx;
    prepareContext(ctx, farm.channel(), std::chrono::seconds(30));
    v1::FetchPlanRequest req;
    req.set_format_version(wire::kFormatVersion);
    req.set_job_id(jobId);
    req.set_first_unit(firstUnit);
    req.set_max_units(maxUnits);
    return stub->FetchPlan(&ctx, req, &page);
  }
};

TEST(FarmPlanPages, PagesCoverEveryUnitOnceAndAFirstUnitBeyondTheEndIsOutOfRange) {
  PlannedJob job;
  constexpr uint32_t kTotal = 40000;
  // Pages of several sizes: 7000 (the last one short), 0 (the server's default) and more than the server
  // gives (capped), each run from unit 0 to the end.
  for (uint32_t maxUnits : {7000u, 0u, 1u << 30}) {
    std::vector<int> seen(kTotal, 0);
    uint32_t first = 0, pages = 0;
    while (first < kTotal) {
      v1::JobPlan page;
      const grpc::Status s = job.fetch(first, maxUnits, page);
      ASSERT_TRUE(s.ok()) << "max_units " << maxUnits << ", first_unit " << first << ": " << s.error_message();
      ASSERT_EQ(page.total_units(), kTotal);
      const uint32_t want = std::min(kTotal - first, maxUnits == 0 || maxUnits > wire::kMaxPlanPageUnits
                                                         ? wire::kMaxPlanPageUnits : maxUnits);
      ASSERT_EQ(uint32_t(page.units_size()), want) << "max_units " << maxUnits << ", first_unit " << first;
      EXPECT_LT(page.ByteSizeLong(), kGrpcDefaultLimit / 2);
      EXPECT_EQ(page.settings().samples().spp(), 40000);
      for (int i = 0; i < page.units_size(); ++i) {
        ASSERT_EQ(page.units(i).index(), first + uint32_t(i));
        ++seen[page.units(i).index()];
        EXPECT_EQ(page.units(i).sample_begin(), page.units(i).index());
      }
      first += uint32_t(page.units_size());
      ++pages;
    }
    for (uint32_t u = 0; u < kTotal; ++u) ASSERT_EQ(seen[u], 1) << "unit " << u << " with max_units " << maxUnits;
    EXPECT_EQ(pages, maxUnits == 7000 ? 6u : 3u) << "max_units " << maxUnits;
  }
  // The last unit alone, then first_unit at and beyond the end: OUT_OF_RANGE naming the field.
  v1::JobPlan page;
  ASSERT_TRUE(job.fetch(kTotal - 1, 5, page).ok());
  ASSERT_EQ(page.units_size(), 1);
  EXPECT_EQ(page.units(0).index(), kTotal - 1);
  for (uint32_t beyond : {kTotal, kTotal + 1, 0xffffffffu}) {
    v1::JobPlan none;
    const grpc::Status s = job.fetch(beyond, 0, none);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::OUT_OF_RANGE) << beyond << ": " << s.error_message();
    EXPECT_NE(s.error_message().find("first_unit"), std::string::npos) << s.error_message();
  }
  // A page alone is not a plan: converting it as one is refused, naming total_units.
  ASSERT_TRUE(job.fetch(0, 100, page).ok());
  try {
    wire::fromProto(page);
    ADD_FAILURE() << "a page of 100 units passed for a whole plan";
  } catch (const wire::WireError& e) {
    EXPECT_EQ(e.field(), "plan.total_units");
  }
}

// The client's side: pages assembled into the whole plan, and pages of different plans refused.
TEST(FarmPlanPages, TheWorkersClientAssemblesThePlanAndRefusesPagesOfAnotherPlan) {
  PlannedJob job;
  auto fetcher = [&](uint32_t maxUnits) {
    return [&job, maxUnits](uint32_t first) {
      v1::JobPlan page;
      const grpc::Status s = job.fetch(first, maxUnits, page);
      if (!s.ok()) throw RpcError(s.error_code(), "FetchPlan", s.error_message());
      return page;
    };
  };
  uint64_t bytes = 0;
  const JobPlan plan = wire::assemblePlanPages(fetcher(0), &bytes);
  ASSERT_EQ(plan.units.size(), 40000u);
  for (size_t i = 0; i < plan.units.size(); ++i) ASSERT_EQ(plan.units[i].index, i);
  EXPECT_EQ(plan.settings.spp, 40000);
  EXPECT_GT(bytes, 40000u * 8);
  // The same through the worker's CoordinatorClient path (fetchPlan).
  const JobPlan viaWorker = fetchPlan(*job.stub, job.farm.channel(), job.jobId);
  EXPECT_EQ(wire::jobPlanBytes(viaWorker), wire::jobPlanBytes(plan));

  // A second page from another plan (other settings, same size; then another total): refused by field.
  auto mixed = [&](auto change) {
    return [&, change](uint32_t first) {
      v1::JobPlan page = fetcher(10000)(first);
      if (first > 0) change(page);
      return page;
    };
  };
  auto expectRefused = [](const std::function<v1::JobPlan(uint32_t)>& f, const std::string& field) {
    try {
      wire::assemblePlanPages(f);
      ADD_FAILURE() << "pages of two plans assembled (" << field << ")";
    } catch (const wire::WireError& e) {
      EXPECT_EQ(e.field(), field) << e.what();
    }
  };
  expectRefused(mixed([](v1::JobPlan& p) { p.mutable_settings()->set_seed(4); }), "plan.settings");
  expectRefused(mixed([](v1::JobPlan& p) { p.mutable_norm()->set_b(2); }), "plan.settings");
  expectRefused(mixed([](v1::JobPlan& p) { p.set_total_units(50000); }), "plan.total_units");
  expectRefused(mixed([](v1::JobPlan& p) { p.clear_units(); }), "plan.units");
  expectRefused(mixed([](v1::JobPlan& p) { p.mutable_units(0)->set_index(7); }), "plan.units.index");
}

}  // namespace
}  // namespace mlt::farm::test
