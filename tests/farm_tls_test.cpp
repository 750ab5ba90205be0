// TLS between the farm's processes (issue 13, transport), end to end with certificates made here by the
// openssl command line: server-side TLS, mutual TLS (client certificates), and the refusals that matter:
// a client that does not trust the server's CA, a client certificate from another CA, an expired server
// or client certificate, a plaintext client. Then a job rendered over mutual TLS with a worker on a
// coordinator listening on all interfaces with no token (the certificates authenticate).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cstdlib>

#include "tests/farm/farm_harness.h"

namespace mlt::farm::test {
namespace {

// A small PKI: ca (trusted), other-ca (not), server and client certificates signed by ca, one client
// certificate signed by other-ca, and expired server and client certificates signed by ca.
class FarmTls : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (std::system("openssl version >/dev/null 2>&1") != 0) return;  // the tests skip
    pki_ = std::make_unique<TempDir>();
    const std::string d = pki_->path;
    const std::string ec = "-newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes";
    std::string script = "set -e; cd '" + d + "'\n";
    for (const char* ca : {"ca", "other-ca"})
      script += fmt::format("openssl req -x509 {} -days 30 -subj /CN={} -keyout {}.key -out {}.pem\n", ec, ca, ca, ca);
    script += "printf 'subjectAltName=IP:127.0.0.1,DNS:localhost\\n' > san.ext\n";
    // name, signing CA, validity in days (-1: notAfter is yesterday, i.e. expired)
    for (auto [name, ca, days] : {std::tuple{"server", "ca", 30}, {"client", "ca", 30}, {"client-other", "other-ca", 30},
                                  {"server-expired", "ca", -1}, {"client-expired", "ca", -1}}) {
      script += fmt::format("openssl req {} -subj /CN={} -keyout {}.key -out {}.csr\n", ec, name, name, name);
      script += fmt::format("openssl x509 -req -in {}.csr -CA {}.pem -CAkey {}.key -CAcreateserial -days {} "
                            "-extfile san.ext -out {}.pem\n", name, ca, ca, days, name);
    }
    std::ofstream(d + "/make.sh") << script;
    ok_ = std::system(("bash '" + d + "/make.sh' >'" + d + "/make.log' 2>&1").c_str()) == 0;
  }
  static void TearDownTestSuite() { pki_.reset(); }
  void SetUp() override {
    if (!pki_) GTEST_SKIP() << "the openssl command line is not installed (deploy/setup.sh installs it)";
    ASSERT_TRUE(ok_) << "openssl failed: " << readFile(pki_->path + "/make.log");
  }
  static std::string pem(const std::string& name) { return pki_->path + "/" + name + ".pem"; }
  static std::string key(const std::string& name) { return pki_->path + "/" + name + ".key"; }

  static std::vector<std::string> serverArgs(const std::string& cert, bool mutual) {
    std::vector<std::string> a{"--tls-cert", pem(cert), "--tls-key", key(cert)};
    if (mutual) a.insert(a.end(), {"--tls-client-ca", pem("ca")});
    return a;
  }
  // ChannelOptions of a client trusting `ca`, presenting `cert` (none if empty).
  static ChannelOptions clientOptions(const std::string& address, const std::string& token, const std::string& ca,
                                      const std::string& cert = "") {
    ChannelOptions o{address, token, ca.empty() ? "" : pem(ca)};
    if (!cert.empty()) {
      o.tlsCert = pem(cert);
      o.tlsKey = key(cert);
    }
    return o;
  }
  static void expectRefused(const ChannelOptions& o, const char* what) {
    try {
      FarmClient(o).list();
      ADD_FAILURE() << what << ": the call succeeded";
    } catch (const RpcError& e) {
      EXPECT_EQ(e.code(), grpc::UNAVAILABLE) << what << ": " << e.what();
    }
  }
  static std::unique_ptr<TempDir> pki_;
  static bool ok_;
};
std::unique_ptr<TempDir> FarmTls::pki_;
bool FarmTls::ok_ = false;

TEST_F(FarmTls, ServerTlsServesClientsThatTrustItsCaOnly) {
  Farm farm;
  farm.token = "s3cret";
  farm.startCoordinator(serverArgs("server", false));
  const std::string addr = farm.coordinator->address;
  EXPECT_NO_THROW(FarmClient(clientOptions(addr, "s3cret", "ca")).list());
  expectRefused(clientOptions(addr, "s3cret", ""), "plaintext client");
  expectRefused(clientOptions(addr, "s3cret", "other-ca"), "client trusting another CA");
  try {  // TLS is no substitute for the token
    FarmClient(clientOptions(addr, "wrong", "ca")).list();
    ADD_FAILURE() << "wrong token accepted over TLS";
  } catch (const RpcError& e) {
    EXPECT_EQ(e.code(), grpc::UNAUTHENTICATED) << e.what();
  }
}

TEST_F(FarmTls, ExpiredServerCertificateIsRefused) {
  Farm farm;
  farm.token = "s3cret";
  farm.startCoordinator(serverArgs("server-expired", false));
  expectRefused(clientOptions(farm.coordinator->address, "s3cret", "ca"), "expired server certificate");
}

TEST_F(FarmTls, MutualTlsNeedsAValidClientCertificateFromItsCa) {
  Farm farm;
  farm.token = "s3cret";
  farm.startCoordinator(serverArgs("server", true));
  const std::string addr = farm.coordinator->address;
  EXPECT_NO_THROW(FarmClient(clientOptions(addr, "s3cret", "ca", "client")).list());
  expectRefused(clientOptions(addr, "s3cret", "ca"), "no client certificate");
  expectRefused(clientOptions(addr, "s3cret", "ca", "client-other"), "client certificate from another CA");
  expectRefused(clientOptions(addr, "s3cret", "ca", "client-expired"), "expired client certificate");
}

TEST_F(FarmTls, JobRendersOverMutualTlsOnAllInterfacesWithoutAToken) {
  Farm farm;
  std::vector<std::string> args{"--listen", "0.0.0.0:0", "--state-dir", farm.stateDir, "--heartbeat", "0.2"};
  for (const std::string& a : serverArgs("server", true)) args.push_back(a);
  farm.coordinator = std::make_unique<CoordinatorProcess>();
  std::vector<std::string> argv{toolsDir() + "/mltfarm-coordinator"};
  argv.insert(argv.end(), args.begin(), args.end());
  farm.coordinator->process = ChildProcess(argv, farm.dir / "coordinator-0.log", true);
  auto line = farm.coordinator->process.readLine(std::chrono::seconds(30));
  ASSERT_TRUE(line && line->rfind("listening on ", 0) == 0) << readFile(farm.dir / "coordinator-0.log");
  const std::string addr = "127.0.0.1:" + line->substr(line->rfind(':') + 1);
  farm.coordinator->address = addr;

  farm.startWorker(1, {"--tls-ca", pem("ca"), "--tls-cert", pem("client"), "--tls-key", key("client")});
  FarmClient c(clientOptions(addr, "", "ca", "client"));
  JobStatus a = c.submit(cornellBox(), tinySettings("pt"));
  JobStatus end = c.watch(a.jobId, [](const JobStatus&) {}, std::chrono::seconds(120));
  EXPECT_EQ(end.state, JobState::Done) << describeStatus(end);
  EXPECT_GT(c.fetch(a.jobId, farm.dir / "out.exr"), 1000u);
  expectRefused(clientOptions(addr, "", "ca"), "no client certificate");
  EXPECT_NE(readFile(farm.dir / "worker-0.log").find("event=uploaded"), std::string::npos);
  EXPECT_NE(readFile(farm.dir / "coordinator-0.log").find("tls=mutual"), std::string::npos);
}

}  // namespace
}  // namespace mlt::farm::test
