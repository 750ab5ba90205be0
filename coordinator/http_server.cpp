// The coordinator's web page and JSON API (see http_server.h).
#include "coordinator/http_server.h"

#include <httplib.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <fmt/format.h>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include "coordinator/auth.h"
#include "coordinator/coordinator.h"
#include "coordinator/http_json.h"
#include "coordinator/web_assets.h"

namespace mlt::farm {
namespace {

using nlohmann::json;

void sendJson(httplib::Response& res, int status, const json& body) {
  res.status = status;
  res.set_header("Cache-Control", "no-store");
  res.set_content(body.dump(), "application/json");
}

int httpStatus(FarmError::Code code) {
  switch (code) {
    case FarmError::Code::InvalidArgument: return 400;
    case FarmError::Code::NotFound: return 404;
    case FarmError::Code::FailedPrecondition: return 409;
    case FarmError::Code::AlreadyExists: return 409;
    case FarmError::Code::Unauthenticated: return 401;
    case FarmError::Code::Unavailable: return 503;
    case FarmError::Code::Internal: return 500;
  }
  return 500;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FarmError(FarmError::Code::Internal, "the result file cannot be read");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::pair<std::string, int> splitListen(const std::string& listen) {
  const size_t colon = listen.rfind(':');
  if (colon == std::string::npos || colon + 1 == listen.size())
    throw std::runtime_error(fmt::format("--http-listen '{}': expected HOST:PORT", listen));
  std::string host = listen.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  int port = 0;
  try {
    port = std::stoi(listen.substr(colon + 1));
  } catch (const std::exception&) {
    port = -1;
  }
  if (port < 0 || port > 65535) throw std::runtime_error(fmt::format("--http-listen '{}': bad port", listen));
  return {host, port};
}

}  // namespace

bool isLoopbackHost(const std::string& listen) {
  const std::string host = splitListen(listen).first;
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

// The handlers, with the preview cache: a job's developed PNG is kept until it has more accepted tasks.
struct HttpServer::Routes {
  Coordinator& c;
  HttpOptions opt;
  std::mutex mu;
  std::map<std::string, PreviewPng> previews;

  bool authorized(const httplib::Request& req, httplib::Response& res) {
    if (opt.token.empty()) return true;
    const std::string h = req.get_header_value("Authorization");
    if (h.rfind("Bearer ", 0) == 0 && constantTimeEquals(std::string_view(h).substr(7), opt.token)) return true;
    res.set_header("WWW-Authenticate", "Bearer");
    sendJson(res, 401, {{"error", "missing or wrong token (Authorization: Bearer ...)"}});
    return false;
  }

  // Runs `body` for an authorized /api/ call, mapping errors onto HTTP statuses.
  template <class F>
  void api(const httplib::Request& req, httplib::Response& res, F&& body) {
    if (!authorized(req, res)) return;
    try {
      body();
    } catch (const FarmError& e) {
      sendJson(res, httpStatus(e.code()), {{"error", e.what()}});
    } catch (const std::exception& e) {
      spdlog::error("http={} {} event=error error=\"{}\"", req.method, req.path, e.what());
      sendJson(res, 500, {{"error", e.what()}});
    }
  }

  const JobSnapshot& findJob(const FarmSnapshot& s, const std::string& id) {
    for (const JobSnapshot& j : s.jobs)
      if (j.status.jobId == id) return j;
    throw FarmError(FarmError::Code::NotFound, fmt::format("no job '{}'", id.substr(0, 64)));
  }

  void preview(const std::string& id, httplib::Response& res) {
    const FarmSnapshot s = c.snapshot();
    const JobSnapshot& j = findJob(s, id);
    PreviewPng p;
    {
      std::lock_guard lock(mu);
      auto it = previews.find(id);
      if (it != previews.end() && it->second.tasks == j.status.tasksDone &&
          it->second.final == (j.status.state == JobState::Done))
        p = it->second;
    }
    if (p.png.empty()) {
      p = c.previewPng(id);
      std::lock_guard lock(mu);
      previews[id] = p;
    }
    res.set_header("Cache-Control", "no-store");
    res.set_header("X-Preview-Tasks", std::to_string(p.tasks));
    res.set_header("X-Preview-Final", p.final ? "1" : "0");
    res.set_content(p.png, "image/png");
  }

  void install(httplib::Server& s) {
    s.Get("/healthz", [](const httplib::Request&, httplib::Response& res) { res.set_content("ok\n", "text/plain"); });
    s.Get("/api/jobs", [this](const httplib::Request& req, httplib::Response& res) {
      api(req, res, [&] {
        json jobs = json::array();
        for (const JobSnapshot& j : c.snapshot().jobs) jobs.push_back(jobJson(j));
        sendJson(res, 200, {{"jobs", jobs}});
      });
    });
    s.Get("/api/workers", [this](const httplib::Request& req, httplib::Response& res) {
      api(req, res, [&] {
        json ws = json::array();
        for (const WorkerSnapshot& w : c.snapshot().workers) ws.push_back(workerJson(w));
        sendJson(res, 200, {{"workers", ws}});
      });
    });
    s.Get(R"(/api/jobs/([^/]+))", [this](const httplib::Request& req, httplib::Response& res) {
      api(req, res, [&] {
        const FarmSnapshot snap = c.snapshot();
        sendJson(res, 200, jobDetailJson(findJob(snap, req.matches[1]), snap.workers));
      });
    });
    s.Get(R"(/api/jobs/([^/]+)/preview\.png)", [this](const httplib::Request& req, httplib::Response& res) {
      api(req, res, [&] { preview(req.matches[1], res); });
    });
    s.Post(R"(/api/jobs/([^/]+)/cancel)", [this](const httplib::Request& req, httplib::Response& res) {
      api(req, res, [&] {
        const std::string id = req.matches[1];
        c.cancel(id);
        spdlog::info("job={} event=cancel_requested via=http peer={}", id, req.remote_addr);
        sendJson(res, 200, jobJson(findJob(c.snapshot(), id)));
      });
    });
    s.Get(R"(/api/jobs/([^/]+)/result\.(exr|png))", [this](const httplib::Request& req, httplib::Response& res) {
      api(req, res, [&] {
        const std::string id = req.matches[1], format = req.matches[2];
        const std::string data = readFile(c.resultPath(id, format));
        res.set_header("Content-Disposition", fmt::format("attachment; filename=\"{}.{}\"", id, format));
        res.set_content(data, format == "png" ? "image/png" : "image/x-exr");
      });
    });
    s.Get(R"(/(|index\.html|job\.html|app\.js|style\.css))", [](const httplib::Request& req, httplib::Response& res) {
      const WebAsset* a = findWebAsset(req.path == "/" ? "/index.html" : req.path);
      if (!a) {
        res.status = 404;
        return;
      }
      res.set_header("Cache-Control", "no-cache");
      res.set_content(reinterpret_cast<const char*>(a->data), a->size, a->contentType);
    });
  }
};

HttpServer::HttpServer(Coordinator& coordinator, HttpOptions options)
    : routes_(new Routes{coordinator, std::move(options)}),
      server_(std::make_unique<httplib::Server>()) {
  const auto [host, port] = splitListen(routes_->opt.listen);
  routes_->install(*server_);
  server_->new_task_queue = [] { return new httplib::ThreadPool(4); };
  port_ = port == 0 ? server_->bind_to_any_port(host) : (server_->bind_to_port(host, port) ? port : -1);
  if (port_ <= 0) throw std::runtime_error(fmt::format("--http-listen {}: cannot listen", routes_->opt.listen));
  thread_ = std::thread([this] { server_->listen_after_bind(); });
}

HttpServer::~HttpServer() { stop(); }

void HttpServer::stop() {
  if (server_) server_->stop();
  if (thread_.joinable()) thread_.join();
}

}  // namespace mlt::farm
