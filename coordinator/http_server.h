// The coordinator's web page and its JSON API (mltfarm-coordinator --http-listen ADDR; off by default),
// served with cpp-httplib beside the gRPC server:
//   GET  /, /job.html, /app.js, /style.css   the page (coordinator/web/, embedded at build time; no data)
//   GET  /healthz                            "ok" (no token)
//   GET  /api/jobs                           {"jobs": [job, ...]}                        (http_json.cpp)
//   GET  /api/jobs/JOB                       job with "acceptance" per path length and "workers"
//   GET  /api/jobs/JOB/preview.png           developed image of the accepted tasks (X-Preview-Tasks: count,
//                                            X-Preview-Final: 1 once it is the finished image); 409 before
//   POST /api/jobs/JOB/cancel                the cancelled job
//   GET  /api/jobs/JOB/result.exr|.png       the finished image, as a download
//   GET  /api/workers                        {"workers": [...]}
// With a token, every /api/ call needs "Authorization: Bearer TOKEN" (401 otherwise; compared in constant
// time); the page asks for it once and keeps it in the tab's sessionStorage. Errors are JSON
// {"error": "..."} with the status of the coordinator's FarmError (404, 409, 400, 500).
#pragma once
#include <memory>
#include <string>
#include <thread>

namespace httplib {
class Server;
}

namespace mlt::farm {

class Coordinator;

struct HttpOptions {
  std::string listen = "127.0.0.1:8080";  // HOST:PORT; port 0 = ephemeral
  std::string token;                      // the coordinator's token; empty = none
};

class HttpServer {
 public:
  // Binds and starts serving; throws std::runtime_error naming the address if it cannot.
  HttpServer(Coordinator& coordinator, HttpOptions options);
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;
  int port() const { return port_; }
  void stop();

 private:
  struct Routes;
  std::unique_ptr<Routes> routes_;
  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
  int port_ = 0;
};

// True for 127.0.0.0/8, ::1 and "localhost" (the page may be served without a token only there).
bool isLoopbackHost(const std::string& listen);

}  // namespace mlt::farm
