#include "common/mlt/strata.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mlt {

size_t strataPixel(float ux, float uy, int width, int height) {
  const int x = std::clamp(int(double(ux) * width), 0, width - 1);
  const int y = std::clamp(int(double(uy) * height), 0, height - 1);
  return size_t(y) * size_t(width) + size_t(x);
}

namespace {

struct Node {
  double n = 0, sum = 0, sumSq = 0;  // the node's samples
  double area = 0;                   // pixels inside the film
  bool ok = false;                   // an estimate exists (n >= 2 somewhere down the chosen cut)
  double est = 0, var = 0;           // sum over the chosen strata of A_r * mean_r and A_r^2 s_r^2 / n_r
  uint64_t strata = 0;
};

// The node's estimate when its samples are pooled.
void pool(Node& node) {
  node.ok = node.n >= 2 && node.area > 0;
  node.strata = node.ok ? 1 : 0;
  if (!node.ok) return;
  const double mean = node.sum / node.n;
  const double s2 = std::max(0.0, (node.sumSq - node.n * mean * mean) / (node.n - 1));
  node.est = node.area * mean;
  node.var = node.area * node.area * s2 / node.n;
}

class Quadtree {
 public:
  Quadtree(std::span<const RGBd> layer, int width, int height) : layer_(layer), w_(width), h_(height) {}

  Node visit(int x0, int y0, int size) const {
    Node node;
    const int x1 = std::min(x0 + size, w_), y1 = std::min(y0 + size, h_);
    if (x0 >= w_ || y0 >= h_) return node;  // outside the film: no pixels
    node.area = double(x1 - x0) * double(y1 - y0);
    if (size == 1) {
      const RGBd& v = layer_[size_t(y0) * size_t(w_) + size_t(x0)];
      node.n = v.r;
      node.sum = v.g;
      node.sumSq = v.b;
      pool(node);
      return node;
    }
    const int half = size / 2;
    Node child[4] = {visit(x0, y0, half), visit(x0 + half, y0, half), visit(x0, y0 + half, half),
                     visit(x0 + half, y0 + half, half)};
    bool split = true;
    for (const Node& c : child) {
      node.n += c.n;
      node.sum += c.sum;
      node.sumSq += c.sumSq;
      if (c.area > 0 && !c.ok) split = false;
    }
    if (!split) {
      pool(node);
      return node;
    }
    node.ok = true;
    for (const Node& c : child) {
      node.est += c.est;
      node.var += c.var;
      node.strata += c.strata;
    }
    return node;
  }

 private:
  std::span<const RGBd> layer_;
  int w_, h_;
};

}  // namespace

StratifiedMean postStratifiedMean(std::span<const RGBd> layer, int width, int height) {
  if (width <= 0 || height <= 0 || layer.size() != size_t(width) * size_t(height))
    throw std::invalid_argument("postStratifiedMean: a layer of " + std::to_string(layer.size()) + " pixels for a " +
                                std::to_string(width) + "x" + std::to_string(height) + " film");
  int size = 1;
  while (size < width || size < height) size *= 2;
  const Node root = Quadtree(layer, width, height).visit(0, 0, size);
  StratifiedMean r;
  r.n = uint64_t(std::llround(root.n));
  r.valid = root.ok;
  if (!r.valid) return r;
  const double P = double(width) * double(height);
  r.mean = root.est / P;
  r.var = root.var / (P * P);
  r.strata = root.strata;
  return r;
}

}  // namespace mlt
