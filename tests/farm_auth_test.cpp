// Who may talk to the coordinator (issue 13, authentication): the token is compared in constant time,
// read from a file or the environment and refused on argv (coordinator, worker, CLI); a coordinator on a
// non-loopback address without a token or client certificates refuses to start unless told --insecure.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdlib>

#include "coordinator/auth.h"
#include "coordinator/service.h"
#include "proto/channel.h"
#include "tests/farm/farm_harness.h"

namespace mlt::farm::test {
namespace {

// Runs `argv` to its end (stdout and stderr into `log`); returns the exit code.
int runToExit(const std::vector<std::string>& argv, const std::string& log) {
  ChildProcess p(argv, log, false);
  auto rc = p.wait(std::chrono::seconds(60));
  EXPECT_TRUE(rc.has_value()) << argv[0] << " did not exit";
  return rc.value_or(-1);
}

// Unsets MLTFARM_TOKEN for the test (the processes it starts inherit the environment) and restores it.
struct NoTokenInEnvironment {
  std::optional<std::string> saved;
  NoTokenInEnvironment() {
    if (const char* t = std::getenv("MLTFARM_TOKEN")) saved = t;
    unsetenv("MLTFARM_TOKEN");
  }
  ~NoTokenInEnvironment() {
    if (saved) setenv("MLTFARM_TOKEN", saved->c_str(), 1);
  }
};

TEST(FarmAuth, ConstantTimeEqualsComparesWholeValues) {
  EXPECT_TRUE(constantTimeEquals("", ""));
  EXPECT_TRUE(constantTimeEquals("Bearer s3cret", "Bearer s3cret"));
  EXPECT_FALSE(constantTimeEquals("Bearer s3cret", "Bearer s3creT"));  // last byte
  EXPECT_FALSE(constantTimeEquals("Bearer s3cret", "Bearer s3cre"));   // a prefix
  EXPECT_FALSE(constantTimeEquals("Bearer s3cret", std::string_view("Bearer s3cret\0", 14)));
  EXPECT_FALSE(constantTimeEquals(std::string_view("a\0b", 3), std::string_view("a\0c", 3)));  // past a NUL
  EXPECT_FALSE(constantTimeEquals("", "x"));
}

TEST(FarmAuth, LoopbackAddressesAreRecognized) {
  for (const char* a : {"127.0.0.1:50051", "127.1.2.3:0", "localhost:50051", "[::1]:50051", "ipv4:127.0.0.1:1",
                        "unix:/tmp/mltfarm.sock"})
    EXPECT_TRUE(isLoopbackListenAddress(a)) << a;
  for (const char* a : {"0.0.0.0:50051", "[::]:50051", "10.0.0.1:50051", "192.168.1.5:0", "example.com:50051",
                        "*:50051", "128.0.0.1:50051", "[::ffff:10.0.0.1]:1"})
    EXPECT_FALSE(isLoopbackListenAddress(a)) << a;
}

TEST(FarmAuth, TokenComesFromItsFileOrTheEnvironment) {
  NoTokenInEnvironment clean;
  TempDir dir;
  writeFileDurably(dir / "token", "s3cret\n", 0600);
  EXPECT_EQ(loadToken(dir / "token"), "s3cret");  // the trailing newline of `echo TOKEN > FILE` is dropped
  EXPECT_EQ(loadToken(""), "");                   // no file, no environment: no token
  setenv("MLTFARM_TOKEN", "from-env", 1);
  EXPECT_EQ(loadToken(""), "from-env");
  EXPECT_EQ(loadToken(dir / "token"), "s3cret");  // the file wins
  unsetenv("MLTFARM_TOKEN");
  auto expectError = [&](const std::string& file, const std::string& needle) {
    try {
      loadToken(file);
      ADD_FAILURE() << file << ": accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << "the error must name the file: " << e.what();
    }
  };
  writeFileDurably(dir / "empty", "\n\n", 0600);
  expectError(dir / "empty", "empty");
  writeFileDurably(dir / "spaced", "two words\n", 0600);
  expectError(dir / "spaced", "byte 4");
  expectError(dir / "missing", "cannot read");
}

// Before: `--token VALUE` was accepted and the token stood in argv for every user to read.
TEST(FarmAuth, TokenOnTheCommandLineIsRefusedByEveryProgram) {
  NoTokenInEnvironment clean;
  TempDir dir;
  const std::vector<std::vector<std::string>> commands = {
      {toolsDir() + "/mltfarm-coordinator", "--listen", "127.0.0.1:0", "--state-dir", dir / "state", "--token", "s3cret"},
      {toolsDir() + "/mltfarm-worker", "--coordinator", "127.0.0.1:1", "--token", "s3cret"},
      {toolsDir() + "/mltfarm", "jobs", "--coordinator", "127.0.0.1:1", "--token", "s3cret"},
  };
  for (size_t i = 0; i < commands.size(); ++i) {
    const std::string log = dir / ("argv-" + std::to_string(i) + ".log");
    EXPECT_NE(runToExit(commands[i], log), 0) << commands[i][0];
    const std::string text = readFile(log);
    EXPECT_NE(text.find("--token-file"), std::string::npos) << commands[i][0] << ": " << text;
    EXPECT_EQ(text.find("listening on"), std::string::npos) << commands[i][0];
  }
}

// Before: a coordinator on 0.0.0.0 with no token served anyone who could reach the port.
TEST(FarmAuth, NonLoopbackListenNeedsATokenOrInsecure) {
  NoTokenInEnvironment clean;
  TempDir dir;
  const std::string bin = toolsDir() + "/mltfarm-coordinator";
  EXPECT_NE(runToExit({bin, "--listen", "0.0.0.0:0", "--state-dir", dir / "open"}, dir / "open.log"), 0);
  const std::string log = readFile(dir / "open.log");
  EXPECT_NE(log.find("not a loopback address"), std::string::npos) << log;
  EXPECT_NE(log.find("--insecure"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(fs::path(dir / "open") / "farm.db")) << "refused before touching the state directory";

  // With a token (from its file), or when told --insecure, it serves; the token is checked.
  writeFileDurably(dir / "token", "s3cret", 0600);
  for (const std::vector<std::string>& extra :
       {std::vector<std::string>{"--token-file", dir / "token"}, std::vector<std::string>{"--insecure"}}) {
    std::vector<std::string> argv{bin, "--listen", "0.0.0.0:0", "--state-dir", dir / "state"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    ChildProcess p(argv, dir / "serving.log", true);
    auto line = p.readLine(std::chrono::seconds(30));
    ASSERT_TRUE(line && line->rfind("listening on 0.0.0.0:", 0) == 0) << extra[0] << ": " << readFile(dir / "serving.log");
    const std::string address = "127.0.0.1:" + line->substr(line->rfind(':') + 1);
    const bool withToken = extra[0] == "--token-file";
    EXPECT_NO_THROW(FarmClient({address, withToken ? "s3cret" : "", ""}).list()) << extra[0];
    if (withToken) {
      try {
        FarmClient({address, "s3creT", ""}).list();
        ADD_FAILURE() << "a wrong token was accepted";
      } catch (const RpcError& e) {
        EXPECT_EQ(e.code(), grpc::UNAUTHENTICATED) << e.what();
      }
    }
    EXPECT_EQ(p.terminate(std::chrono::seconds(10)), 0);
  }

  // The same rule for in-process servers (startServer calls it), which tests and embedders use.
  ServerOptions so;
  so.listen = "0.0.0.0:0";
  EXPECT_THROW(checkListenPolicy(so), std::runtime_error);
  so.tlsClientCa = "ca.pem";  // client certificates authenticate too
  EXPECT_NO_THROW(checkListenPolicy(so));
}

}  // namespace
}  // namespace mlt::farm::test
