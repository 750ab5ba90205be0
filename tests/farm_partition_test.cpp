// A network partition (issue 13, durability): a worker in its own network namespace, joined to the
// coordinator's by a veth pair, loses the link in the middle of the job (while it holds a lease); the
// coordinator gives the lease away; the link comes back; the job completes, byte-identical to an
// undisturbed run. Needs root and `ip netns` (iproute2): skipped with the reason where they are missing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cstdlib>

#include "tests/farm/farm_harness.h"

namespace mlt::farm::test {
namespace {

int sh(const std::string& cmd) { return std::system((cmd + " >/dev/null 2>&1").c_str()); }

// A namespace with one end of a veth pair (10.213.N.2/30); the other end (10.213.N.1/30) stays here.
struct NetNs {
  std::string ns, host, peer, hostIp, peerIp;
  bool up = false;
  std::string why;
  NetNs() {
    const unsigned n = unsigned(getpid()) % 250 + 1;
    ns = fmt::format("mltfarm-part-{}", getpid());
    host = fmt::format("mfh{}", getpid() % 1000000);
    peer = fmt::format("mfw{}", getpid() % 1000000);
    hostIp = fmt::format("10.213.{}.1", n);
    peerIp = fmt::format("10.213.{}.2", n);
    if (geteuid() != 0) {
      why = "not root (ip netns and veth need CAP_NET_ADMIN)";
      return;
    }
    if (sh("ip netns add " + ns) != 0) {
      why = "`ip netns add` failed (no iproute2, or no network namespaces in this container)";
      return;
    }
    up = sh("ip link add " + host + " type veth peer name " + peer) == 0 &&
         sh("ip link set " + peer + " netns " + ns) == 0 && sh("ip addr add " + hostIp + "/30 dev " + host) == 0 &&
         sh("ip link set " + host + " up") == 0 && sh(exec("ip addr add " + peerIp + "/30 dev " + peer)) == 0 &&
         sh(exec("ip link set " + peer + " up")) == 0 && sh(exec("ip link set lo up")) == 0;
    if (!up) why = "could not set up a veth pair between network namespaces";
  }
  ~NetNs() {
    sh("ip netns del " + ns);
    sh("ip link del " + host);
  }
  std::string exec(const std::string& cmd) const { return "ip netns exec " + ns + " " + cmd; }
  void setLink(bool on) const { ASSERT_EQ(sh("ip link set " + host + (on ? " up" : " down")), 0); }
};

TEST(FarmPartition, WorkerCutOffMidTaskRejoinsAndTheImageIsByteIdentical) {
  NetNs net;
  if (!net.up) GTEST_SKIP() << "network namespaces unavailable: " << net.why;
  if (sh(net.exec("true")) != 0) GTEST_SKIP() << "`ip netns exec` does not work here";

  // The undisturbed run: the same job with a worker on loopback.
  std::string reference;
  {
    Farm farm;
    farm.startCoordinator();
    farm.startWorker(1);
    JobStatus a = farm.client().submit(cornellBox(), tinySettings("pssmlt"));
    ASSERT_EQ(farm.waitDone(a.jobId).state, JobState::Done);
    farm.client().fetch(a.jobId, farm.dir / "reference.exr");
    reference = readFile(farm.dir / "reference.exr");
  }

  Farm farm;
  farm.token = "s3cret";  // listening on every interface: a token is required
  farm.startCoordinator({}, "0.0.0.0:0");
  const std::string port = farm.coordinator->address.substr(farm.coordinator->address.rfind(':') + 1);
  farm.coordinator->address = "127.0.0.1:" + port;  // the test's own calls
  // The worker, in the namespace, dials the coordinator across the veth pair. Each task is held a
  // while so that tasks are in flight when the link goes.
  std::vector<std::string> argv{"ip", "netns", "exec", net.ns, toolsDir() + "/mltfarm-worker", "--coordinator",
                                net.hostIp + ":" + port, "--threads", "1", "--token-file", farm.tokenFile(),
                                "--cache-dir", farm.dir / "cache", "--debug-task-delay-ms", "150"};
  std::string ip = "/usr/sbin/ip";
  if (!fs::exists(ip)) ip = "/sbin/ip";
  argv[0] = ip;
  farm.workers.push_back(std::make_unique<ChildProcess>(argv, farm.dir / "worker-0.log", false));

  auto c = farm.client();
  JobStatus a = c.submit(cornellBox(), tinySettings("pssmlt"));
  JobStatus s = farm.waitFor(a.jobId, [](const JobStatus& s) { return s.tasksDone >= 2 && s.leasedTasks >= 1; });
  ASSERT_EQ(s.state, JobState::Running) << "the job ended before the partition; make it longer";
  net.setLink(false);
  // Cut off: the coordinator stops hearing from the worker and requeues its lease.
  const std::string log0 = farm.dir / "coordinator-0.log";
  for (int i = 0; i < 1200 && readFile(log0).find("event=lease_expired") == std::string::npos; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_NE(readFile(log0).find("event=lease_expired"), std::string::npos) << "the lease never expired";
  const JobStatus during = c.get(a.jobId);
  EXPECT_EQ(during.state, JobState::Running);
  net.setLink(true);
  EXPECT_EQ(farm.waitDone(a.jobId).state, JobState::Done);
  c.fetch(a.jobId, farm.dir / "out.exr");
  EXPECT_EQ(readFile(farm.dir / "out.exr"), reference) << "the partition changed the image";
  EXPECT_GT(c.get(a.jobId).tasksDone, during.tasksDone) << "the worker did not come back";
}

}  // namespace
}  // namespace mlt::farm::test
