#include "common/mlt/importance.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace mlt {

int importanceTileSize(int width, int height) {
  const int side = std::max(width, height);
  return std::max(1, (side + kImportanceMaxTiles - 1) / kImportanceMaxTiles);
}

ImportanceMap importanceGrid(int filmWidth, int filmHeight) {
  if (filmWidth <= 0 || filmHeight <= 0)
    throw std::invalid_argument("importance map: film size " + std::to_string(filmWidth) + "x" +
                                std::to_string(filmHeight) + " must be positive");
  ImportanceMap m;
  m.filmWidth = filmWidth;
  m.filmHeight = filmHeight;
  m.tileSize = importanceTileSize(filmWidth, filmHeight);
  m.tilesX = (filmWidth + m.tileSize - 1) / m.tileSize;
  m.tilesY = (filmHeight + m.tileSize - 1) / m.tileSize;
  return m;
}

ImportanceMap importanceFromTileSums(int filmWidth, int filmHeight, const std::vector<double>& tileSums,
                                     const std::vector<uint64_t>& tileCounts, double floor) {
  ImportanceMap m = importanceGrid(filmWidth, filmHeight);
  if (!(floor > 0 && std::isfinite(floor)))
    throw std::invalid_argument("importance map: the floor must be positive and finite, got " + std::to_string(floor));
  const size_t tiles = size_t(m.tilesX) * size_t(m.tilesY);
  if (tileSums.size() != tiles || tileCounts.size() != tiles)
    throw std::invalid_argument("importance map: " + std::to_string(tileSums.size()) + " tile sums and " +
                                std::to_string(tileCounts.size()) + " counts for " + std::to_string(tiles) + " tiles");
  double total = 0, n = 0;
  for (size_t i = 0; i < tiles; ++i) {
    total += tileSums[i];
    n += double(tileCounts[i]);
  }
  const double gbar = n > 0 ? total / n : 0.0;
  if (!(gbar > 0 && std::isfinite(gbar))) return {};  // nothing seen: luminance
  // g: the 3 x 3 box of tiles around each tile (pooled sums over pooled counts).
  std::vector<double> g(tiles, 0.0);
  for (int y = 0; y < m.tilesY; ++y)
    for (int x = 0; x < m.tilesX; ++x) {
      double s = 0, c = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (xx < 0 || yy < 0 || xx >= m.tilesX || yy >= m.tilesY) continue;
          s += tileSums[size_t(yy) * size_t(m.tilesX) + size_t(xx)];
          c += double(tileCounts[size_t(yy) * size_t(m.tilesX) + size_t(xx)]);
        }
      g[size_t(y) * size_t(m.tilesX) + size_t(x)] = c > 0 ? s / c : 0.0;
    }
  const double floor2 = (floor * gbar) * (floor * gbar);
  std::vector<double> h(tiles);
  double weighted = 0;  // sum over samples of h g: the scale below makes its mean gbar
  for (size_t i = 0; i < tiles; ++i) {
    h[i] = 1.0 / std::sqrt(g[i] * g[i] + floor2);  // (R2)
    weighted += double(tileCounts[i]) * h[i] * g[i];
  }
  const double scale = weighted > 0 ? gbar * n / weighted : 1.0;
  m.h.resize(tiles);
  for (size_t i = 0; i < tiles; ++i) m.h[i] = float(h[i] * scale);
  return m;
}

void validateImportanceMap(const ImportanceMap& m, const char* field) {
  if (m.empty()) return;
  const std::string f(field);
  if (m.filmWidth <= 0 || m.filmHeight <= 0)
    throw std::invalid_argument(f + ": film size " + std::to_string(m.filmWidth) + "x" + std::to_string(m.filmHeight) +
                                " must be positive");
  const ImportanceMap grid = importanceGrid(m.filmWidth, m.filmHeight);
  const int T = grid.tileSize, X = grid.tilesX, Y = grid.tilesY;
  if (m.tileSize != T || m.tilesX != X || m.tilesY != Y)
    throw std::invalid_argument(f + ": tiles of " + std::to_string(m.tileSize) + " pixels, " + std::to_string(m.tilesX) +
                                "x" + std::to_string(m.tilesY) + ", where the film takes " + std::to_string(T) + ", " +
                                std::to_string(X) + "x" + std::to_string(Y));
  if (m.h.size() != size_t(X) * size_t(Y))
    throw std::invalid_argument(f + ": " + std::to_string(m.h.size()) + " values for " + std::to_string(X * Y) + " tiles");
  for (size_t i = 0; i < m.h.size(); ++i)
    if (!(m.h[i] > 0 && std::isfinite(m.h[i])))
      throw std::invalid_argument(f + ": tile " + std::to_string(i) + " holds " + std::to_string(m.h[i]) +
                                  " (must be positive and finite)");
}

}  // namespace mlt
