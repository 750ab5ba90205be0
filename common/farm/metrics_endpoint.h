// GET /metrics for the coordinator and the worker (--metrics-listen HOST:PORT): prometheus-cpp's
// Exposer (its embedded civetweb) serving the given collectables. Header only: the farm's processes link
// prometheus-cpp::pull, the rest of common/ does not.
#pragma once
#include <prometheus/collectable.h>
#include <prometheus/exposer.h>

#include <fmt/format.h>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace mlt::farm {

struct MetricsEndpoint {
  std::vector<std::shared_ptr<prometheus::Collectable>> collectables;  // kept alive while served
  std::unique_ptr<prometheus::Exposer> exposer;                        // stopped before they go
  int port = 0;                                                        // the bound port (port 0 = ephemeral)
};

// Throws std::runtime_error naming the address when it cannot listen.
inline MetricsEndpoint startMetricsEndpoint(const std::string& listen,
                                            std::vector<std::shared_ptr<prometheus::Collectable>> collectables) {
  MetricsEndpoint m;
  try {
    m.exposer = std::make_unique<prometheus::Exposer>(listen, 1);
  } catch (const std::exception& e) {
    throw std::runtime_error(fmt::format("--metrics-listen {}: cannot listen ({})", listen, e.what()));
  }
  m.collectables = std::move(collectables);
  for (const auto& c : m.collectables) m.exposer->RegisterCollectable(c);
  const std::vector<int> ports = m.exposer->GetListeningPorts();
  if (ports.empty()) throw std::runtime_error(fmt::format("--metrics-listen {}: no listening port", listen));
  m.port = ports.front();
  return m;
}

}  // namespace mlt::farm
