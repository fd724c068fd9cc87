// Analytic ray-shape intersections (see geometry.hpp for the references).
#include "kestrel/sensors/geometry.hpp"

namespace kestrel::sensors {

namespace {

inline void set_normal(LocalHit& hit, real x, real y, real z) {
  hit.n[0] = x;
  hit.n[1] = y;
  hit.n[2] = z;
}

// Roots of t^2 + 2 b t + c = 0 (d unit, so the quadratic's leading coefficient is 1 for spheres).
// Returns the smaller root inside [tmin, tmax], else the larger one if inside.
inline bool smallest_root(real a, real b, real c, real tmin, real tmax, real& t) {
  // a t^2 + 2 b t + c = 0
  const real disc = b * b - a * c;
  if (disc < 0 || a <= 0) return false;
  const real sq = std::sqrt(disc);
  const real t0 = (-b - sq) / a;
  if (t0 >= tmin && t0 <= tmax) {
    t = t0;
    return true;
  }
  const real t1 = (-b + sq) / a;
  if (t1 >= tmin && t1 <= tmax) {
    t = t1;
    return true;
  }
  return false;
}

}  // namespace

bool intersect_box(const real o[3], const real d[3], const real h[3], real tmin, real tmax, LocalHit& hit) {
  real tn = -1e30_r, tf = 1e30_r;
  int an = 0, af = 0;
  for (int k = 0; k < 3; ++k) {
    if (std::fabs(d[k]) < 1e-20_r) {
      if (o[k] < -h[k] || o[k] > h[k]) return false;
      continue;
    }
    const real inv = 1 / d[k];
    real t0 = (-h[k] - o[k]) * inv, t1 = (h[k] - o[k]) * inv;
    if (t0 > t1) {
      const real tmp = t0;
      t0 = t1;
      t1 = tmp;
    }
    if (t0 > tn) {
      tn = t0;
      an = k;
    }
    if (t1 < tf) {
      tf = t1;
      af = k;
    }
  }
  if (tn > tf) return false;
  real n[3] = {0, 0, 0};
  if (tn >= tmin) {
    if (tn > tmax) return false;
    hit.t = tn;
    n[an] = d[an] > 0 ? -1_r : 1_r;  // entry face faces the ray
  } else {
    if (tf < tmin || tf > tmax) return false;
    hit.t = tf;
    n[af] = d[af] > 0 ? 1_r : -1_r;  // exit face, outward
  }
  set_normal(hit, n[0], n[1], n[2]);
  return true;
}

bool intersect_sphere(const real o[3], const real d[3], real radius, real tmin, real tmax, LocalHit& hit) {
  const real a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  const real b = o[0] * d[0] + o[1] * d[1] + o[2] * d[2];
  const real c = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - radius * radius;
  real t;
  if (!smallest_root(a, b, c, tmin, tmax, t)) return false;
  hit.t = t;
  const real inv_r = 1 / radius;
  set_normal(hit, (o[0] + t * d[0]) * inv_r, (o[1] + t * d[1]) * inv_r, (o[2] + t * d[2]) * inv_r);
  return true;
}

namespace {

// Lateral surface of the infinite cylinder x^2 + y^2 = r^2, restricted to |z| <= half_length.
inline bool cylinder_side(const real o[3], const real d[3], real radius, real half_length, real tmin, real tmax,
                          LocalHit& hit) {
  const real a = d[0] * d[0] + d[1] * d[1];
  if (a < 1e-20_r) return false;
  const real b = o[0] * d[0] + o[1] * d[1];
  const real c = o[0] * o[0] + o[1] * o[1] - radius * radius;
  const real disc = b * b - a * c;
  if (disc < 0) return false;
  const real sq = std::sqrt(disc);
  const real roots[2] = {(-b - sq) / a, (-b + sq) / a};
  for (real t : roots) {
    if (t < tmin || t > tmax) continue;
    const real z = o[2] + t * d[2];
    if (z < -half_length || z > half_length) continue;
    hit.t = t;
    const real inv_r = 1 / radius;
    set_normal(hit, (o[0] + t * d[0]) * inv_r, (o[1] + t * d[1]) * inv_r, 0);
    return true;
  }
  return false;
}

}  // namespace

bool intersect_cylinder(const real o[3], const real d[3], real radius, real half_length, real tmin, real tmax,
                        LocalHit& hit) {
  bool found = cylinder_side(o, d, radius, half_length, tmin, tmax, hit);
  if (std::fabs(d[2]) > 1e-20_r) {
    for (int s = 0; s < 2; ++s) {
      const real zc = s == 0 ? -half_length : half_length;
      const real t = (zc - o[2]) / d[2];
      const real lim = found ? hit.t : tmax;
      if (t < tmin || t > lim) continue;
      const real x = o[0] + t * d[0], y = o[1] + t * d[1];
      if (x * x + y * y > radius * radius) continue;
      if (found && t == hit.t) continue;  // rim: keep the side hit (deterministic choice)
      hit.t = t;
      set_normal(hit, 0, 0, s == 0 ? -1_r : 1_r);
      found = true;
    }
  }
  return found;
}

bool intersect_capsule(const real o[3], const real d[3], real radius, real half_length, real tmin, real tmax,
                       LocalHit& hit) {
  bool found = cylinder_side(o, d, radius, half_length, tmin, tmax, hit);
  for (int s = 0; s < 2; ++s) {
    const real zc = s == 0 ? -half_length : half_length;
    const real oc[3] = {o[0], o[1], o[2] - zc};
    LocalHit h;
    if (!intersect_sphere(oc, d, radius, tmin, found ? hit.t : tmax, h)) continue;
    if (found && h.t >= hit.t) continue;
    hit = h;
    found = true;
  }
  return found;
}

bool intersect_plane(const real o[3], const real d[3], real tmin, real tmax, LocalHit& hit) {
  if (std::fabs(d[2]) < 1e-20_r) return false;
  const real t = -o[2] / d[2];
  if (t < tmin || t > tmax) return false;
  hit.t = t;
  set_normal(hit, 0, 0, 1);
  return true;
}

void triangle_normal(const real v0[3], const real v1[3], const real v2[3], real n[3]) {
  const real e1[3] = {v1[0] - v0[0], v1[1] - v0[1], v1[2] - v0[2]};
  const real e2[3] = {v2[0] - v0[0], v2[1] - v0[1], v2[2] - v0[2]};
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  const real len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  const real inv = len > 0 ? 1 / len : 0;
  n[0] *= inv;
  n[1] *= inv;
  n[2] *= inv;
}

}  // namespace kestrel::sensors
