// Authentication of the coordinator's callers (see auth.h).
#include "coordinator/auth.h"

#include <arpa/inet.h>

#include <fmt/format.h>
#include <fstream>
#include <stdexcept>

#include "common/core/sha256.h"
#include "coordinator/service.h"

namespace mlt::farm {
namespace {

std::string readPem(const std::string& path, const char* what) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot read the {}", path, what));
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::array<uint8_t, 32> digestOf(std::string_view s) {
  Sha256 h;
  h.update(s.data(), s.size());
  return h.digest();
}

}  // namespace

bool constantTimeEquals(std::string_view a, std::string_view b) {
  const std::array<uint8_t, 32> da = digestOf(a), db = digestOf(b);
  volatile uint8_t diff = 0;  // volatile: the loop must not stop at the first difference
  for (size_t i = 0; i < da.size(); ++i) diff = diff | uint8_t(da[i] ^ db[i]);
  return diff == 0;
}

TokenCheck::TokenCheck(const std::string& token) : enabled_(!token.empty()), expected_("Bearer " + token) {}

grpc::Status TokenCheck::check(const grpc::ServerContext& ctx) const {
  if (!enabled_) return grpc::Status::OK;
  bool ok = false;
  auto [begin, end] = ctx.client_metadata().equal_range("authorization");
  for (auto it = begin; it != end; ++it)  // every value is compared: no early exit on a match either
    ok = constantTimeEquals(std::string_view(it->second.data(), it->second.size()), expected_) || ok;
  if (ok) return grpc::Status::OK;
  return grpc::Status(grpc::StatusCode::UNAUTHENTICATED, "missing or wrong token (authorization: Bearer ...)");
}

bool isLoopbackListenAddress(const std::string& listen) {
  if (listen.rfind("unix:", 0) == 0 || listen.rfind("unix-abstract:", 0) == 0) return true;
  std::string host;
  if (listen.rfind("ipv4:", 0) == 0 || listen.rfind("ipv6:", 0) == 0) host = listen.substr(5);
  else host = listen;
  if (!host.empty() && host.front() == '[') {
    const size_t close = host.find(']');
    if (close == std::string::npos) return false;
    host = host.substr(1, close - 1);
  } else if (const size_t colon = host.rfind(':'); colon != std::string::npos && host.find(':') == colon) {
    host = host.substr(0, colon);  // host:port (an IPv6 address without brackets has several colons)
  }
  if (host == "localhost") return true;
  in_addr v4{};
  if (inet_pton(AF_INET, host.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  in6_addr v6{};
  if (inet_pton(AF_INET6, host.c_str(), &v6) == 1) return IN6_IS_ADDR_LOOPBACK(&v6);
  return false;  // a host name or a wildcard (0.0.0.0, ::, *)
}

void checkListenPolicy(const ServerOptions& o) {
  if (o.insecure || !o.token.empty() || !o.tlsClientCa.empty() || isLoopbackListenAddress(o.listen)) return;
  throw std::runtime_error(fmt::format(
      "--listen {}: not a loopback address, and neither a token (--token-file FILE or MLTFARM_TOKEN) nor client "
      "certificates (--tls-client-ca) are required: anyone who reaches the port could submit jobs and upload "
      "results. Give one of them, or --insecure if that is really meant",
      o.listen));
}

std::shared_ptr<grpc::ServerCredentials> serverCredentials(const ServerOptions& o) {
  if (o.tlsCert.empty() && o.tlsKey.empty()) {
    if (!o.tlsClientCa.empty()) throw std::runtime_error("--tls-client-ca needs --tls-cert and --tls-key");
    return grpc::InsecureServerCredentials();
  }
  if (o.tlsCert.empty() || o.tlsKey.empty()) throw std::runtime_error("--tls-cert and --tls-key must be given together");
  grpc::SslServerCredentialsOptions ssl(o.tlsClientCa.empty() ? GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE
                                                              : GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY);
  ssl.pem_key_cert_pairs.push_back({readPem(o.tlsKey, "TLS private key"), readPem(o.tlsCert, "TLS certificate")});
  if (!o.tlsClientCa.empty()) ssl.pem_root_certs = readPem(o.tlsClientCa, "client CA certificate");
  return grpc::SslServerCredentials(ssl);
}

}  // namespace mlt::farm
