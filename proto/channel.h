// Channel helpers shared by every gRPC client of the coordinator (the worker's CoordinatorClient, the
// CLI's FarmClient, tests): the channel (plain or TLS), the per-call token and deadline, and RpcError,
// the exception a failed call becomes (its gRPC status code and message).
#pragma once
#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>

namespace mlt::farm {

class RpcError : public std::runtime_error {
 public:
  RpcError(grpc::StatusCode code, const std::string& rpc, const std::string& message);
  grpc::StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
 private:
  grpc::StatusCode code_;
  std::string message_;
};

struct ChannelOptions {
  std::string address;   // host:port
  std::string token;     // sent as "authorization: Bearer TOKEN" when set
  std::string tlsCa;     // PEM root certificate: TLS on when set
  std::string tlsCert, tlsKey;  // PEM client certificate chain and key (mutual TLS); both or neither
  std::string tlsServerName;    // name the server certificate must carry, when not the address's host
};
std::shared_ptr<grpc::Channel> makeChannel(const ChannelOptions& o);
// Adds the token and a deadline to a context.
void prepareContext(grpc::ClientContext& ctx, const ChannelOptions& o, std::chrono::milliseconds deadline);
// The shared token, never from argv (any user of the machine reads argv in ps or /proc): from
// `tokenFile` when given, else from $MLTFARM_TOKEN, else empty (no token). Trailing whitespace (a newline)
// is dropped; an empty file or one with other whitespace or control characters is an error naming it.
std::string loadToken(const std::string& tokenFile);
// The error for the removed `--token VALUE` flag (kept only to say what replaces it).
std::string tokenOnCommandLineError();
const char* statusCodeName(grpc::StatusCode code);
// A failure worth retrying after a backoff (the coordinator is away, restarting or overloaded), as
// opposed to one that retrying cannot fix (bad input, unknown job, wrong token).
bool isTransient(grpc::StatusCode code);

}  // namespace mlt::farm
