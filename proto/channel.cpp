// Channel helpers (see channel.h).
#include "proto/channel.h"

#include <fmt/format.h>

#include <cctype>
#include <cstdlib>
#include <fstream>

namespace mlt::farm {
namespace {

std::string readAll(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot read", path));
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

std::string loadToken(const std::string& tokenFile) {
  std::string token, where;
  if (!tokenFile.empty()) {
    token = readAll(tokenFile);
    where = tokenFile;
  } else if (const char* t = std::getenv("MLTFARM_TOKEN")) {
    token = t;
    where = "MLTFARM_TOKEN";
  } else {
    return {};
  }
  while (!token.empty() && std::isspace(static_cast<unsigned char>(token.back()))) token.pop_back();
  if (token.empty()) throw std::runtime_error(fmt::format("{}: the token is empty", where));
  if (token.size() > 4096) throw std::runtime_error(fmt::format("{}: the token is longer than 4096 bytes", where));
  for (size_t i = 0; i < token.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(token[i]);
    if (c <= ' ' || c >= 0x7f)  // it travels in an HTTP/2 header: printable ASCII only
      throw std::runtime_error(
          fmt::format("{}: byte {} of the token is whitespace or not printable ASCII", where, i + 1));
  }
  return token;
}

std::string tokenOnCommandLineError() {
  return "--token: a token on the command line is visible to every user of the machine (ps, /proc); "
         "put it in a file readable only by you and pass --token-file FILE, or set MLTFARM_TOKEN";
}

const char* statusCodeName(grpc::StatusCode c) {
  switch (c) {
    case grpc::OK: return "OK";
    case grpc::CANCELLED: return "CANCELLED";
    case grpc::UNKNOWN: return "UNKNOWN";
    case grpc::INVALID_ARGUMENT: return "INVALID_ARGUMENT";
    case grpc::DEADLINE_EXCEEDED: return "DEADLINE_EXCEEDED";
    case grpc::NOT_FOUND: return "NOT_FOUND";
    case grpc::ALREADY_EXISTS: return "ALREADY_EXISTS";
    case grpc::PERMISSION_DENIED: return "PERMISSION_DENIED";
    case grpc::UNAUTHENTICATED: return "UNAUTHENTICATED";
    case grpc::RESOURCE_EXHAUSTED: return "RESOURCE_EXHAUSTED";
    case grpc::FAILED_PRECONDITION: return "FAILED_PRECONDITION";
    case grpc::ABORTED: return "ABORTED";
    case grpc::OUT_OF_RANGE: return "OUT_OF_RANGE";
    case grpc::UNIMPLEMENTED: return "UNIMPLEMENTED";
    case grpc::INTERNAL: return "INTERNAL";
    case grpc::UNAVAILABLE: return "UNAVAILABLE";
    case grpc::DATA_LOSS: return "DATA_LOSS";
    default: return "?";
  }
}

RpcError::RpcError(grpc::StatusCode code, const std::string& rpc, const std::string& message)
    : std::runtime_error(fmt::format("{}: {}: {}", rpc, statusCodeName(code), message)), code_(code), message_(message) {}

std::shared_ptr<grpc::Channel> makeChannel(const ChannelOptions& o) {
  std::shared_ptr<grpc::ChannelCredentials> creds;
  if (o.tlsCert.empty() != o.tlsKey.empty())
    throw std::runtime_error("--tls-cert and --tls-key (the client certificate) must be given together");
  if (!o.tlsCert.empty() && o.tlsCa.empty())
    throw std::runtime_error("--tls-cert: a client certificate needs --tls-ca (the coordinator's root certificate)");
  grpc::ChannelArguments args;
  if (!o.tlsCa.empty()) {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = readAll(o.tlsCa);
    if (!o.tlsCert.empty()) {
      ssl.pem_cert_chain = readAll(o.tlsCert);
      ssl.pem_private_key = readAll(o.tlsKey);
    }
    creds = grpc::SslCredentials(ssl);
    if (!o.tlsServerName.empty()) args.SetSslTargetNameOverride(o.tlsServerName);
  } else {
    if (!o.tlsServerName.empty()) throw std::runtime_error("--tls-server-name needs --tls-ca");
    creds = grpc::InsecureChannelCredentials();
  }
  args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 100);
  args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 2000);
  return grpc::CreateCustomChannel(o.address, creds, args);
}

void prepareContext(grpc::ClientContext& ctx, const ChannelOptions& o, std::chrono::milliseconds deadline) {
  ctx.set_deadline(std::chrono::system_clock::now() + deadline);
  if (!o.token.empty()) ctx.AddMetadata("authorization", "Bearer " + o.token);
}

bool isTransient(grpc::StatusCode c) {
  return c == grpc::UNAVAILABLE || c == grpc::DEADLINE_EXCEEDED || c == grpc::CANCELLED || c == grpc::UNKNOWN ||
         c == grpc::INTERNAL || c == grpc::RESOURCE_EXHAUSTED;
}

}  // namespace mlt::farm
