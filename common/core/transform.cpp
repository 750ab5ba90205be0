#include "common/core/transform.h"

#include <stdexcept>

namespace mlt {

Transform Transform::translate(const Vec3& d) {
  Transform t;
  t.m[0][3] = d.x;
  t.m[1][3] = d.y;
  t.m[2][3] = d.z;
  return t;
}

Transform Transform::scale(const Vec3& s) {
  Transform t;
  t.m[0][0] = s.x;
  t.m[1][1] = s.y;
  t.m[2][2] = s.z;
  return t;
}

Transform Transform::rotate(const Vec3& axisIn, double angleDegrees) {
  const double len = std::sqrt(double(axisIn.x) * axisIn.x + double(axisIn.y) * axisIn.y + double(axisIn.z) * axisIn.z);
  if (!(len > 0)) throw std::runtime_error("rotation axis has zero length");
  const double x = axisIn.x / len, y = axisIn.y / len, z = axisIn.z / len;
  const double theta = angleDegrees * 3.14159265358979323846 / 180.0;
  const double s = std::sin(theta), c = std::cos(theta), C = 1 - c;
  Transform t;
  t.m[0] = {x * x * C + c, x * y * C - z * s, x * z * C + y * s, 0};
  t.m[1] = {y * x * C + z * s, y * y * C + c, y * z * C - x * s, 0};
  t.m[2] = {z * x * C - y * s, z * y * C + x * s, z * z * C + c, 0};
  return t;
}

Transform Transform::lookAt(const Vec3& origin, const Vec3& target, const Vec3& up) {
  auto norm = [](double v[3]) {
    const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(l > 0)) throw std::runtime_error("lookat: degenerate direction");
    for (int i = 0; i < 3; ++i) v[i] /= l;
  };
  double dir[3] = {double(target.x) - origin.x, double(target.y) - origin.y, double(target.z) - origin.z};
  norm(dir);
  double u[3] = {up.x, up.y, up.z};
  norm(u);
  // left = up x dir (Mitsuba convention: camera +x points left in world when looking down +z)
  double left[3] = {u[1] * dir[2] - u[2] * dir[1], u[2] * dir[0] - u[0] * dir[2], u[0] * dir[1] - u[1] * dir[0]};
  const double ll = std::sqrt(left[0] * left[0] + left[1] * left[1] + left[2] * left[2]);
  if (!(ll > 0)) throw std::runtime_error("lookat: 'up' is parallel to the viewing direction");
  for (double& v : left) v /= ll;
  double newUp[3] = {dir[1] * left[2] - dir[2] * left[1], dir[2] * left[0] - dir[0] * left[2],
                     dir[0] * left[1] - dir[1] * left[0]};
  Transform t;
  for (int i = 0; i < 3; ++i) {
    t.m[i][0] = left[i];
    t.m[i][1] = newUp[i];
    t.m[i][2] = dir[i];
    t.m[i][3] = (&origin.x)[i];
  }
  return t;
}

Transform Transform::operator*(const Transform& o) const {
  Transform r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += m[i][k] * o.m[k][j];
      r.m[i][j] = s;
    }
  return r;
}

Transform Transform::transpose() const {
  Transform r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r.m[i][j] = m[j][i];
  return r;
}

bool Transform::isFinite() const {
  for (const auto& row : m)
    for (double v : row)
      if (!std::isfinite(v)) return false;
  return true;
}

bool Transform::isSimilarity() const {
  const Vec3 ax = vector(Vec3(1, 0, 0)), ay = vector(Vec3(0, 1, 0)), az = vector(Vec3(0, 0, 1));
  const float lx = length(ax), ly = length(ay), lz = length(az);
  const float tol = 1e-4f * std::fmax(lx, std::fmax(ly, lz));
  return lx > 0 && ly > 0 && lz > 0 && std::fabs(lx - ly) <= tol && std::fabs(lx - lz) <= tol &&
         std::fabs(dot(ax, ay)) <= tol * lx && std::fabs(dot(ax, az)) <= tol * lx && std::fabs(dot(ay, az)) <= tol * lx;
}

double Transform::determinant3x3() const {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

// Gauss-Jordan elimination with partial pivoting.
Transform Transform::inverse() const {
  double a[4][8];
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      a[i][j] = m[i][j];
      a[i][j + 4] = (i == j) ? 1.0 : 0.0;
    }
  for (int c = 0; c < 4; ++c) {
    int piv = c;
    for (int r = c + 1; r < 4; ++r)
      if (std::fabs(a[r][c]) > std::fabs(a[piv][c])) piv = r;
    if (std::fabs(a[piv][c]) < 1e-300) throw std::runtime_error("transform is singular and cannot be inverted");
    if (piv != c)
      for (int j = 0; j < 8; ++j) std::swap(a[c][j], a[piv][j]);
    const double inv = 1.0 / a[c][c];
    for (int j = 0; j < 8; ++j) a[c][j] *= inv;
    for (int r = 0; r < 4; ++r) {
      if (r == c) continue;
      const double f = a[r][c];
      if (f == 0) continue;
      for (int j = 0; j < 8; ++j) a[r][j] -= f * a[c][j];
    }
  }
  Transform r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r.m[i][j] = a[i][j + 4];
  return r;
}

Vec3 Transform::point(const Vec3& p) const {
  double r[4];
  for (int i = 0; i < 4; ++i) r[i] = m[i][0] * p.x + m[i][1] * p.y + m[i][2] * p.z + m[i][3];
  if (r[3] != 1.0 && r[3] != 0.0)
    for (int i = 0; i < 3; ++i) r[i] /= r[3];
  return {float(r[0]), float(r[1]), float(r[2])};
}

Vec3 Transform::vector(const Vec3& v) const {
  return {float(m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z), float(m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z),
          float(m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z)};
}

Vec3 Transform::normal(const Vec3& n) const {
  const Transform inv = inverse();
  // (M^-1)^T n
  return {float(inv.m[0][0] * n.x + inv.m[1][0] * n.y + inv.m[2][0] * n.z),
          float(inv.m[0][1] * n.x + inv.m[1][1] * n.y + inv.m[2][1] * n.z),
          float(inv.m[0][2] * n.x + inv.m[1][2] * n.y + inv.m[2][2] * n.z)};
}

}  // namespace mlt
