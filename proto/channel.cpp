// Channel helpers (see channel.h).
#include "proto/channel.h"

#include <fmt/format.h>
#include <fstream>

namespace mlt::farm {
namespace {

std::string readAll(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot read", path));
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

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
  if (!o.tlsCa.empty()) {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = readAll(o.tlsCa);
    creds = grpc::SslCredentials(ssl);
  } else {
    creds = grpc::InsecureChannelCredentials();
  }
  grpc::ChannelArguments args;
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
