// gRPC transport for the coordinator: the two services (clients, workers) and the server around them.
// They do transport only (auth token, version checks, chunk assembly, status codes) and call the
// handler interfaces of coordinator/handler.h. Health checking and server reflection are on.
#pragma once
#include <grpcpp/grpcpp.h>
#include <grpcpp/impl/codegen/service_type.h>

#include <functional>
#include <memory>
#include <string>

#include "coordinator/handler.h"

namespace mlt::farm {

struct ServerOptions {
  std::string listen = "127.0.0.1:50051";  // loopback unless told otherwise; port 0 = ephemeral
  std::string token;                       // if set, every call must carry "authorization: Bearer TOKEN"
  std::string tlsCert, tlsKey;             // PEM files; both or neither
  // Told of every UploadResult that reached the handler: film bytes received, seconds from its first
  // message to the reply (metrics). Optional.
  std::function<void(uint64_t bytes, double seconds)> onUpload;
  std::string tlsClientCa;                 // PEM CA: client certificates are required and checked (mutual TLS)
  bool insecure = false;                   // allow a non-loopback address with neither token nor client CA
};

struct RunningServer {
  std::unique_ptr<grpc::Service> clientService, workerService;
  std::unique_ptr<grpc::Server> server;
  int port = 0;  // the bound port (useful with port 0)
};

// Builds and starts the server; throws std::runtime_error if it cannot bind.
RunningServer startServer(const ServerOptions& options, ClientHandler& clients, WorkerHandler& workers);

// Maps a handler exception onto a gRPC status (FarmError code, WireError -> INVALID_ARGUMENT,
// anything else -> INTERNAL). Exposed for tests.
grpc::Status statusFromException(std::exception_ptr e);

}  // namespace mlt::farm
