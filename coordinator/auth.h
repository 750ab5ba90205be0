// Who may talk to the coordinator: the shared token (compared in constant time), the server's TLS
// credentials (server-side, or mutual with client certificates), and the rule that a coordinator
// reachable from other machines is never open to anyone by accident.
#pragma once
#include <grpcpp/grpcpp.h>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

namespace mlt::farm {

struct ServerOptions;

// True when a and b hold the same bytes, in a time that depends on neither their contents nor their
// lengths: both are hashed (SHA-256) and the digests compared without an early exit.
bool constantTimeEquals(std::string_view a, std::string_view b);

// Checks the "authorization: Bearer TOKEN" metadata of a call against the configured token.
class TokenCheck {
 public:
  explicit TokenCheck(const std::string& token);  // empty: every call passes
  bool enabled() const { return enabled_; }
  // OK, or UNAUTHENTICATED when no authorization value carries the token.
  grpc::Status check(const grpc::ServerContext& ctx) const;

 private:
  bool enabled_ = false;
  std::string expected_;  // "Bearer TOKEN"
};

// True for addresses only this machine can reach: 127.0.0.0/8, ::1, localhost, unix sockets.
bool isLoopbackListenAddress(const std::string& listen);

// Throws std::runtime_error when `o` would serve anyone who can reach a non-loopback port: no token and
// no client certificates, unless o.insecure says that is meant.
void checkListenPolicy(const ServerOptions& o);

// Plain, TLS (tlsCert + tlsKey) or mutual TLS (plus tlsClientCa: client certificates are required and
// verified against it). Throws std::runtime_error naming the file that cannot be read.
std::shared_ptr<grpc::ServerCredentials> serverCredentials(const ServerOptions& o);

}  // namespace mlt::farm
