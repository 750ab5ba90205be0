#include "tests/support/mesh_density.h"

#include <cmath>

namespace mlt::test {

double hitTriangle(const Vec3& o, const Vec3& w, const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  const double e1[3] = {p1.x - p0.x, p1.y - p0.y, p1.z - p0.z}, e2[3] = {p2.x - p0.x, p2.y - p0.y, p2.z - p0.z};
  const double d[3] = {w.x, w.y, w.z}, tv[3] = {o.x - p0.x, o.y - p0.y, o.z - p0.z};
  auto cr = [](const double* a, const double* b, double* c) {
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
  };
  auto dt = [](const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  double pv[3], qv[3];
  cr(d, e2, pv);
  const double det = dt(e1, pv);
  if (std::fabs(det) < 1e-14) return -1;
  const double u = dt(tv, pv) / det;
  if (u < 0 || u > 1) return -1;
  cr(tv, e1, qv);
  const double v = dt(d, qv) / det;
  if (v < 0 || u + v > 1) return -1;
  const double t = dt(e2, qv) / det;
  return t > 0 ? t : -1;
}

double meshPdfW(const Light& light, const MeshDesc& m, const Vec3& ref, const Vec3& w) {
  double pdf = 0;
  for (size_t i = 0; i < m.indices.size(); i += 3) {
    const Vec3 &p0 = m.positions[m.indices[i]], &p1 = m.positions[m.indices[i + 1]], &p2 = m.positions[m.indices[i + 2]];
    const Vec3 n = cross(p1 - p0, p2 - p0);
    if (!(lengthSquared(n) > 0)) continue;
    const double t = hitTriangle(ref, w, p0, p1, p2);
    if (t > 0) pdf += light.pdfLi(ref, ref + w * float(t), normalize(n), w);
  }
  return pdf;
}

}  // namespace mlt::test
