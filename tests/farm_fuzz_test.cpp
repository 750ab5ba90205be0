// Fuzzing with a seeded random mutator (issue 13, "what must show"): a fixed number of mutated inputs,
// the same on every run (seed kSeed; a failure names the iteration to replay), over
//   - the scene loader (mutated copies of the bundled scenes, their referenced files beside them),
//   - the bundle reader/writer (mutated bundle paths: nothing may land outside the bundle's directory),
//   - the partial-EXR merge (mutated partials of a real tiny job),
//   - every RPC request message of both services (random and mutated protobufs, sent raw to an
//     in-process coordinator over loopback).
// The property: no crash (a clean exception or gRPC status is fine), and the coordinator still serves
// and still plans jobs afterwards. The file-format targets run in a child process (fork) with an
// address-space limit, so that a mutated size that makes the code allocate gigabytes fails there with
// std::bad_alloc instead of taking the machine's memory; a crash there is reported with its iteration.
// Built with AddressSanitizer + UndefinedBehaviorSanitizer in CI (tools/run-tests.sh, build-asan).
#include <gtest/gtest.h>
#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <grpcpp/generic/generic_stub.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <fmt/format.h>

#include <cstdlib>
#include <random>
#include <set>

#include "common/core/durable_file.h"
#include "common/farm/bundle.h"
#include "common/farm/scene_loading.h"
#include "common/methods/registry.h"
#include "coordinator/coordinator.h"
#include "coordinator/merge.h"
#include "coordinator/service.h"
#include "tests/farm/farm_harness.h"

#if defined(__SANITIZE_ADDRESS__)
#define MLTFARM_ASAN 1
// A mutated size may ask for gigabytes: under ASan such a request fails (std::bad_alloc) instead of
// taking the machine's memory (RLIMIT_AS cannot be used with ASan's shadow memory).
extern "C" const char* __asan_default_options() { return "allocator_may_return_null=1:max_allocation_size_mb=1024"; }
#endif

namespace mlt::farm::test {
namespace {

namespace pb = google::protobuf;
using Rng = std::mt19937_64;
constexpr uint64_t kSeed = 13;

size_t pick(Rng& rng, size_t n) { return n == 0 ? 0 : size_t(rng() % n); }

// --- mutations ---------------------------------------------------------------------------------------

// Byte-level edits: flips, interesting bytes and 32-bit integers, deletions, duplications, insertions,
// truncation.
std::string mutateBytes(std::string s, Rng& rng, int edits) {
  static const uint32_t kInts[] = {0, 1, 0x7f, 0x80, 0xff, 0x7fff, 0xffff, 8192, 16384, 65536, 0x40000000, 0x7fffffff,
                                   0x80000000, 0xffffffff};
  for (int e = 0; e < edits; ++e) {
    const size_t at = pick(rng, s.size() + 1);
    switch (rng() % 7) {
      case 0: if (at < s.size()) s[at] = char(s[at] ^ (1 << (rng() % 8))); break;
      case 1: if (at < s.size()) s[at] = char("\x00\xff\x7f\x80\x01"[rng() % 5]); break;
      case 2: {
        const uint32_t v = kInts[pick(rng, std::size(kInts))];
        if (at + 4 <= s.size()) std::memcpy(s.data() + at, &v, 4);
        break;
      }
      case 3: s.erase(std::min(at, s.size()), 1 + pick(rng, 16)); break;
      case 4: if (at < s.size()) s.insert(at, s.substr(at, 1 + pick(rng, 64))); break;
      case 5: s.insert(at, std::string(1 + pick(rng, 8), char(rng()))); break;
      default: if (rng() % 8 == 0) s.resize(pick(rng, s.size() + 1)); break;
    }
  }
  return s;
}

// Text edits for scene files: numbers replaced by extreme ones, attribute values by hostile ones, then a
// few byte edits.
std::string mutateText(std::string s, Rng& rng) {
  static const char* kNumbers[] = {"0", "-1", "1e308", "-1e308", "nan", "inf", "-inf", "65536", "2147483648",
                                   "4294967296", "1e-320", "180", "2000", "16385", "0x10", "1,2", ""};
  static const char* kValues[] = {"", "../../farm.db", "/etc/passwd", "meshes/../../x.obj", "a\\b", "%s%n",
                                  "\xff\xfe", "$undefined", "0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0"};
  const int edits = 1 + int(rng() % 3);
  for (int e = 0; e < edits; ++e) {
    const size_t at = pick(rng, s.size());
    if (rng() % 2) {  // a number
      const size_t b = s.find_first_of("0123456789", at);
      if (b == std::string::npos) continue;
      size_t end = s.find_first_not_of("0123456789.e-+", b);
      if (end == std::string::npos) end = s.size();
      s.replace(b, end - b, kNumbers[pick(rng, std::size(kNumbers))]);
    } else {  // an attribute value
      const size_t q = s.find("value=\"", at);
      if (q == std::string::npos) continue;
      const size_t end = s.find('"', q + 7);
      if (end == std::string::npos) continue;
      s.replace(q + 7, end - q - 7, kValues[pick(rng, std::size(kValues))]);
    }
  }
  return rng() % 3 == 0 ? mutateBytes(std::move(s), rng, 1 + int(rng() % 3)) : s;
}

// --- isolation of the file-format targets ------------------------------------------------------------

// Runs `body(progress)` in a child process with at most 2 GiB of address space (outside ASan); `progress`
// records the iteration about to run. Expects the child to exit 0; reports the iteration it died in.
template <class F>
void runIsolated(const std::string& name, const std::string& dir, F&& body) {
  const std::string progressFile = dir + "/" + name + ".progress";
  std::fflush(nullptr);
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
#ifndef MLTFARM_ASAN
    const rlimit limit{rlim_t(2) << 30, rlim_t(2) << 30};
    setrlimit(RLIMIT_AS, &limit);
#endif
    int rc = 0;
    try {
      rc = body([&](int iteration) {
        std::ofstream(progressFile, std::ios::trunc) << iteration;
      });
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: setup failed: %s\n", name.c_str(), e.what());
      rc = 3;
    }
    std::fflush(nullptr);
    _exit(rc);
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  const std::string at = readFile(progressFile);
  if (WIFSIGNALED(status))
    ADD_FAILURE() << name << ": crashed with signal " << WTERMSIG(status) << " at iteration " << at << " (seed "
                  << kSeed << ")";
  else
    EXPECT_EQ(WEXITSTATUS(status), 0) << name << ": exit code " << WEXITSTATUS(status) << " at iteration " << at;
}

// --- the scene loader and the bundle ---------------------------------------------------------------

TEST(FarmFuzz, SceneLoaderSurvivesMutatedScenes) {
  TempDir dir;
  runIsolated("scene-loader", dir.path, [&](auto progress) {
    Rng rng(kSeed);
    std::vector<std::string> seeds;  // each seed's scene file, copied with every file it references
    for (const char* scene : {"cornell-box.xml", "door-ajar.xml", "glossy-plates.xml", "textured-serialized.xml",
                              "furnace-sphere.xml", "checker-spheres.pbrt"}) {
      const SceneBundle b = collectBundle(std::string(MLTFARM_SOURCE_DIR) + "/scenes/" + scene);
      const std::string copy = dir / (std::string("seed-") + scene);
      writeBundle(copy, b.files);
      seeds.push_back(copy + "/" + b.sceneFile);
    }
    int errors = 0;
    constexpr int kIterations = 600;
    for (int i = 0; i < kIterations; ++i) {
      progress(i);
      const std::string& seed = seeds[pick(rng, seeds.size())];
      const std::string ext = fs::path(seed).extension().string();
      const std::string mutated = fs::path(seed).parent_path().string() + "/fuzz" + ext;
      std::ofstream(mutated, std::ios::binary | std::ios::trunc) << mutateText(readFile(seed), rng);
      try {
        loadSceneDesc(mutated);
      } catch (const std::exception&) {
        ++errors;
      }
      if (i % 4 == 0) {  // the bundle collected from the mutated scene stays inside its directory
        try {
          for (const BundleFile& f : collectBundle(mutated).files) validateBundlePath(f.path);
        } catch (const std::exception&) {
        }
      }
    }
    std::fprintf(stderr, "scene loader: %d mutated scenes, %d clean errors\n", kIterations, errors);
    return errors > 0 && errors < kIterations ? 0 : 2;  // the mutator must reach both outcomes
  });
}

TEST(FarmFuzz, BundleWriterKeepsEveryFileInsideTheBundle) {
  TempDir dir;
  runIsolated("bundle", dir.path, [&](auto progress) {
    Rng rng(kSeed);
    const std::string sandbox = dir / "sandbox";
    fs::create_directories(sandbox);
    const std::vector<std::string> kPaths = {"scene.xml", "meshes/a.obj", "a/b/c/d.ply", "../escaped",
                                             "a/../../escaped", "/" + (dir / "escaped"), "a//b", "a\\b", "", ".", "..",
                                             "./a", "a/./b", "a/", std::string(300, 'x'), std::string("nul\0x", 5),
                                             "tex/\xff\xfe.png", "a/b/../c"};
    int written = 0;
    constexpr int kIterations = 300;
    for (int i = 0; i < kIterations; ++i) {
      progress(i);
      std::vector<BundleFile> files;
      std::set<std::string> seen;
      for (size_t n = 1 + pick(rng, 4); files.size() < n;) {
        std::string p = kPaths[pick(rng, kPaths.size())];
        if (rng() % 3 == 0) p = mutateBytes(p, rng, 1);
        if (!seen.insert(p).second) continue;
        files.push_back({p, mutateBytes("data", rng, int(rng() % 3))});
      }
      const std::string bundle = sandbox + "/b" + std::to_string(i);
      bool ok = true;
      try {
        writeBundle(bundle, files);
      } catch (const std::exception&) {
        ok = false;
      }
      // Nothing outside the bundle's directory, whatever the paths said.
      for (const auto& e : fs::directory_iterator(dir.path))
        if (e.path().filename() != "sandbox" && e.path().extension() != ".progress") {
          std::fprintf(stderr, "iteration %d: %s written outside the bundle\n", i, e.path().c_str());
          return 1;
        }
      for (const auto& e : fs::directory_iterator(sandbox))
        if (e.path().filename().string().rfind("b", 0) != 0) {
          std::fprintf(stderr, "iteration %d: %s written outside the bundle\n", i, e.path().c_str());
          return 1;
        }
      if (!ok) continue;
      ++written;
      std::sort(files.begin(), files.end(), [](auto& a, auto& b) { return a.path < b.path; });
      const std::vector<BundleFile> back = readBundle(bundle);  // what was written reads back whole
      if (back.size() != files.size()) {
        std::fprintf(stderr, "iteration %d: %zu files written, %zu read back\n", i, files.size(), back.size());
        return 1;
      }
      for (size_t k = 0; k < back.size(); ++k)
        if (back[k].path != files[k].path || back[k].data != files[k].data) {
          std::fprintf(stderr, "iteration %d: '%s' read back as '%s'\n", i, files[k].path.c_str(), back[k].path.c_str());
          return 1;
        }
      if (bundleHash(back) != bundleHash(files)) return 1;
    }
    return written > 0 && written < kIterations ? 0 : 2;
  });
}

// --- the partial-EXR merge ---------------------------------------------------------------------------

TEST(FarmFuzz, PartialExrMergeSurvivesMutatedPartials) {
  TempDir dir;
  runIsolated("merge", dir.path, [&](auto progress) {
    // A real tiny job (pt, 16x16, 4 units): its tasks' partial EXRs and their merge as the seed.
    wire::SubmittedSettings sub = tinySettings("pt");
    sub.settings.width = sub.settings.height = 16;
    sub.settings.spp = 4;
    auto scene = buildRenderScene(loadSceneDesc(cornellBox()), sub.settings.width, sub.settings.height);
    const JobPlan plan = planJob(*scene, sub.settings);
    const std::vector<TaskRange> tasks = splitTasks(plan);
    const JobIdentity id{"job-1", "0123456789abcdef", "cornell-box.xml"};
    std::vector<std::string> parts, bytes;
    for (uint32_t t = 0; t < tasks.size(); ++t) {
      PartialResult r;
      runTask(*scene, plan, tasks[t], r);
      parts.push_back(dir / ("task-" + std::to_string(t) + ".exr"));
      writePartialExr(parts.back(), id, plan, t, r);
      bytes.push_back(readFile(parts.back()));
    }
    mergePartialExrs(parts, dir / "reference.exr", "");  // the unmutated parts merge
    Rng rng(kSeed);
    int errors = 0;
    constexpr int kIterations = 250;
    for (int i = 0; i < kIterations; ++i) {
      progress(i);
      std::vector<std::string> inputs = parts;
      for (int m = 0, n = 1 + int(rng() % 2); m < n; ++m) {
        const size_t k = pick(rng, parts.size());
        inputs[k] = dir / ("mutated-" + std::to_string(m) + ".exr");
        std::ofstream(inputs[k], std::ios::binary | std::ios::trunc) << mutateBytes(bytes[k], rng, 1 + int(rng() % 4));
      }
      try {
        mergePartialExrs(inputs, dir / "out.exr", "");
      } catch (const std::exception&) {
        ++errors;
      }
    }
    std::fprintf(stderr, "merge: %d mutated merges, %d clean errors\n", kIterations, errors);
    return errors > 0 ? 0 : 2;
  });
}

// --- every RPC request message ---------------------------------------------------------------------

// Fills a message with random values: interesting numbers, hostile strings, nested messages, repeated
// fields; format_version is right most of the time so that the requests get past the version check.
void randomFill(pb::Message& m, Rng& rng, const std::vector<std::string>& strings, int depth) {
  const pb::Descriptor* d = m.GetDescriptor();
  const pb::Reflection* r = m.GetReflection();
  static const int64_t kInts[] = {0, 1, -1, 2, 7, 64, 1000, 16384, 16385, 65536, 1 << 20, 1 << 30, INT32_MAX,
                                  INT32_MIN, INT64_MAX, INT64_MIN};
  static const double kDoubles[] = {0, 1, -1, 0.5, 1e300, -1e300, 1e-320, NAN, INFINITY, -INFINITY};
  for (int i = 0; i < d->field_count(); ++i) {
    const pb::FieldDescriptor* f = d->field(i);
    if (rng() % 3 == 0) continue;
    const int n = f->is_repeated() ? int(rng() % 4) : 1;
    for (int k = 0; k < n; ++k) {
      const int64_t iv = rng() % 4 == 0 ? int64_t(rng()) : kInts[pick(rng, std::size(kInts))];
      const double dv = rng() % 4 == 0 ? double(int64_t(rng())) * 1e-3 : kDoubles[pick(rng, std::size(kDoubles))];
      const bool version = f->name() == "format_version" && rng() % 5 != 0;
      const std::string sv = strings[pick(rng, strings.size())];
      switch (f->cpp_type()) {
        case pb::FieldDescriptor::CPPTYPE_INT32:
          f->is_repeated() ? r->AddInt32(&m, f, int32_t(iv)) : r->SetInt32(&m, f, int32_t(iv));
          break;
        case pb::FieldDescriptor::CPPTYPE_INT64:
          f->is_repeated() ? r->AddInt64(&m, f, iv) : r->SetInt64(&m, f, iv);
          break;
        case pb::FieldDescriptor::CPPTYPE_UINT32: {
          const uint32_t v = version ? uint32_t(wire::kFormatVersion) : uint32_t(iv);
          f->is_repeated() ? r->AddUInt32(&m, f, v) : r->SetUInt32(&m, f, v);
          break;
        }
        case pb::FieldDescriptor::CPPTYPE_UINT64:
          f->is_repeated() ? r->AddUInt64(&m, f, uint64_t(iv)) : r->SetUInt64(&m, f, uint64_t(iv));
          break;
        case pb::FieldDescriptor::CPPTYPE_DOUBLE:
          f->is_repeated() ? r->AddDouble(&m, f, dv) : r->SetDouble(&m, f, dv);
          break;
        case pb::FieldDescriptor::CPPTYPE_FLOAT:
          f->is_repeated() ? r->AddFloat(&m, f, float(dv)) : r->SetFloat(&m, f, float(dv));
          break;
        case pb::FieldDescriptor::CPPTYPE_BOOL:
          f->is_repeated() ? r->AddBool(&m, f, rng() % 2) : r->SetBool(&m, f, rng() % 2);
          break;
        case pb::FieldDescriptor::CPPTYPE_ENUM: {
          const int v = rng() % 4 == 0 ? int(iv) : f->enum_type()->value(int(pick(rng, f->enum_type()->value_count())))->number();
          f->is_repeated() ? r->AddEnumValue(&m, f, v) : r->SetEnumValue(&m, f, v);
          break;
        }
        case pb::FieldDescriptor::CPPTYPE_STRING:
          f->is_repeated() ? r->AddString(&m, f, sv) : r->SetString(&m, f, sv);
          break;
        case pb::FieldDescriptor::CPPTYPE_MESSAGE:
          if (depth < 4) randomFill(f->is_repeated() ? *r->AddMessage(&m, f) : *r->MutableMessage(&m, f), rng, strings, depth + 1);
          break;
      }
    }
  }
}

// One raw call of `method` ("/pkg.Service/Method"): writes `requests`, reads every response. Returns the
// status (the property is that there is one: the server answered and lives).
grpc::Status rawCall(grpc::GenericStub& stub, const std::string& method, const std::vector<std::string>& requests,
                     const std::string& token, std::chrono::milliseconds deadline) {
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + deadline);
  if (!token.empty()) ctx.AddMetadata("authorization", "Bearer " + token);
  grpc::CompletionQueue cq;
  std::unique_ptr<grpc::GenericClientAsyncReaderWriter> call = stub.PrepareCall(&ctx, method, &cq);
  void* tag = nullptr;
  bool ok = false;
  auto await = [&] { return cq.Next(&tag, &ok) && ok; };
  call->StartCall(nullptr);
  bool open = await();
  for (const std::string& req : requests) {
    if (!open) break;
    grpc::Slice slice(req);
    grpc::ByteBuffer buffer(&slice, 1);
    call->Write(buffer, nullptr);
    open = await();
  }
  if (open) {
    call->WritesDone(nullptr);
    await();
    for (int reads = 0; reads < 10000; ++reads) {
      grpc::ByteBuffer response;
      call->Read(&response, nullptr);
      if (!await()) break;
    }
  }
  grpc::Status status;
  call->Finish(&status, nullptr);
  cq.Next(&tag, &ok);
  cq.Shutdown();
  while (cq.Next(&tag, &ok)) {
  }
  return status;
}

TEST(FarmFuzz, CoordinatorSurvivesRandomAndMutatedRequestsOnEveryRpc) {
  TempDir dir;
  CoordinatorOptions co;
  co.stateDir = dir / "state";
  co.leaseWaitSeconds = 0.02;
  co.leaseTimeoutSeconds = 0.5;
  Coordinator coordinator(co);
  ServerOptions so;
  so.listen = "127.0.0.1:0";
  so.token = "s3cret";
  RunningServer server = startServer(so, coordinator, coordinator);
  const ChannelOptions channel{"127.0.0.1:" + std::to_string(server.port), "s3cret", ""};
  FarmClient client(channel);

  // A real job first, so that ids, hashes and tasks in the random requests can name something real.
  const wire::SubmittedSettings settings = tinySettings("pt");
  const JobStatus job = client.submit(cornellBox(), settings);
  const std::string sceneHash = job.sceneHash;
  // The valid SubmitJob stream (header + chunks), a seed for structure-aware mutations.
  v1::SubmitJobRequest header;
  header.mutable_header()->set_format_version(wire::kFormatVersion);
  *header.mutable_header()->mutable_settings() = wire::toProto(settings);
  const SceneBundle bundle = collectBundle(cornellBox());
  header.mutable_header()->set_bundle_scene_file(bundle.sceneFile);
  std::vector<std::string> validSubmit{header.SerializeAsString()};
  for (const BundleFile& f : bundle.files) {
    v1::SubmitJobRequest c;
    c.mutable_chunk()->set_path(f.path);
    c.mutable_chunk()->set_data(f.data);
    c.mutable_chunk()->set_last(true);
    validSubmit.push_back(c.SerializeAsString());
  }

  const std::vector<std::string> strings = {"", job.jobId, "job-2", "job-0", "job-999999999999", sceneHash,
                                            "cornell-box.xml", "../../farm.db", "/etc/passwd", "w-1", "lease-1",
                                            std::string(70000, 'a'), std::string("\0\xff\n", 3), "png", "exr",
                                            "job-1/../../x"};
  grpc::GenericStub stub(makeChannel(channel));
  Rng rng(kSeed);
  std::map<int, int> codes;
  int calls = 0;
  for (const char* name : {v1::Coordinator::service_full_name(), v1::WorkerService::service_full_name()}) {
    const pb::ServiceDescriptor* service = pb::DescriptorPool::generated_pool()->FindServiceByName(name);
    ASSERT_NE(service, nullptr) << name;
    for (int mi = 0; mi < service->method_count(); ++mi) {
      const pb::MethodDescriptor* method = service->method(mi);
      const std::string path = "/" + service->full_name() + "/" + method->name();
      const pb::Message* prototype = pb::MessageFactory::generated_factory()->GetPrototype(method->input_type());
      constexpr int kPerMethod = 60;
      for (int i = 0; i < kPerMethod; ++i) {
        std::vector<std::string> requests;
        const int kind = int(rng() % 4);
        if (kind == 3 && method->name() == "SubmitJob") {  // the valid stream with one message changed
          requests = validSubmit;
          std::unique_ptr<pb::Message> m(prototype->New());
          const size_t k = pick(rng, requests.size());
          m->ParseFromString(requests[k]);
          randomFill(*m->GetReflection()->MutableMessage(m.get(), m->GetDescriptor()->field(k == 0 ? 0 : 1)), rng,
                     strings, 1);
          requests[k] = m->SerializeAsString();
        } else {
          const int count = method->client_streaming() ? int(rng() % 4) : (rng() % 10 == 0 ? 0 : 1);
          for (int c = 0; c < count; ++c) {
            std::unique_ptr<pb::Message> m(prototype->New());
            randomFill(*m, rng, strings, 0);
            std::string bytes = m->SerializeAsString();
            if (kind == 1) bytes = mutateBytes(bytes, rng, 1 + int(rng() % 3));  // often not a valid message
            requests.push_back(std::move(bytes));
          }
        }
        const std::string token = rng() % 10 == 0 ? "wrong" : "s3cret";
        const grpc::Status s = rawCall(stub, path, requests, token, std::chrono::milliseconds(1500));
        ++codes[int(s.error_code())];
        ++calls;
      }
    }
  }
  std::string summary;
  for (auto [code, n] : codes) summary += fmt::format(" {}x{}", statusCodeName(grpc::StatusCode(code)), n);
  std::fprintf(stderr, "rpc fuzz: %d calls:%s\n", calls, summary.c_str());
  EXPECT_GT(codes[grpc::INVALID_ARGUMENT], 0) << "the requests never got past the transport";

  // The coordinator still serves, and its background threads still plan and merge: a new job runs.
  EXPECT_NO_THROW(client.list());
  const JobStatus after = client.submit(cornellBox(), tinySettings("bdpt"));
  JobStatus s = client.get(after.jobId);
  for (int i = 0; i < 600 && (s.state == JobState::Queued || s.state == JobState::Planning); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    s = client.get(after.jobId);
  }
  EXPECT_EQ(s.state, JobState::Running) << describeStatus(s);
  coordinator.stop();
  server.server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
}

}  // namespace
}  // namespace mlt::farm::test
