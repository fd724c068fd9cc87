// Ray primitives of the sensor core: axis-aligned boxes, rays, hits and the analytic ray-shape
// intersections every scene object reduces to.
//
// All shapes are intersected in their own (local) frame: a scene instance carries a rigid pose,
// the ray is moved into the local frame once (R^T (o - p), R^T d) and, because the transform is
// rigid, the hit distance t is the same in both frames. Directions are unit vectors, so t is a
// range in metres.
//
// Algorithms:
//  - ray/box slab test: T. L. Kay, J. T. Kajiya, "Ray tracing complex scenes", SIGGRAPH 1986;
//    the min/max form with precomputed inverse directions of A. Williams, S. Barrus, R. K. Morley,
//    P. Shirley, "An efficient and robust ray-box intersection algorithm", JGT 2005, and
//    A. Majercik et al., "A ray-box intersection algorithm and efficient dynamic voxel rendering",
//    JCGT 2018.
//  - ray/triangle: T. Möller, B. Trumbore, "Fast, minimum storage ray-triangle intersection",
//    JGT 1997 (two-sided; sensors see both faces of thin geometry).
//  - sphere, cylinder and capsule: closed-form quadratics (no tessellation, so a trunk is exactly
//    round at any range).
#pragma once

#include <cmath>
#include <cstdint>

#include "kestrel/kernel/types.hpp"

namespace kestrel::sensors {

/// Axis-aligned bounding box. An empty box has lo > hi.
struct Aabb {
  real lo[3] = {1e30_r, 1e30_r, 1e30_r};
  real hi[3] = {-1e30_r, -1e30_r, -1e30_r};

  void grow(const real p[3]) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = p[k] < lo[k] ? p[k] : lo[k];
      hi[k] = p[k] > hi[k] ? p[k] : hi[k];
    }
  }
  void grow(const Aabb& b) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = b.lo[k] < lo[k] ? b.lo[k] : lo[k];
      hi[k] = b.hi[k] > hi[k] ? b.hi[k] : hi[k];
    }
  }
  bool empty() const { return lo[0] > hi[0]; }
  /// Half the surface area (the SAH only compares areas, the factor 2 cancels).
  real half_area() const {
    if (empty()) return 0;
    const real dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    return dx * dy + dy * dz + dz * dx;
  }
  real centroid(int k) const { return (lo[k] + hi[k]) * 0.5_r; }
};

/// A ray with its inverse direction precomputed (every box test reuses it).
struct Ray {
  real o[3];
  real d[3];
  real inv_d[3];
};

/// Zero direction components are nudged to a tiny value of the same sign so that 1/d is finite
/// and the slab test never forms 0 * inf = NaN (the robust variant of Williams et al. 2005).
inline Ray make_ray(const real o[3], const real d[3]) {
  Ray r;
  for (int k = 0; k < 3; ++k) {
    r.o[k] = o[k];
    r.d[k] = d[k];
    real dk = d[k];
    if (std::fabs(dk) < 1e-20_r) dk = std::signbit(dk) ? -1e-20_r : 1e-20_r;
    r.inv_d[k] = 1 / dk;
  }
  return r;
}

/// Slab test. Returns the entry distance in tnear_out; true when [tmin, tmax] overlaps the box.
/// The comparison is inclusive so that boxes touching the current best hit are still visited
/// (needed for the stable-id tie break of equal-distance hits).
/// The slab test itself, on an origin and inverse direction given apart (a packet keeps its rays'
/// inverse directions in columns: mesh.cpp's packet_ray_box).
inline bool slab_box(const real o[3], const real inv_d[3], const real lo[3], const real hi[3], real tmin, real tmax,
                     real& tnear_out) {
  real tn = tmin, tf = tmax;
  for (int k = 0; k < 3; ++k) {
    const real t0 = (lo[k] - o[k]) * inv_d[k];
    const real t1 = (hi[k] - o[k]) * inv_d[k];
    const real a = t0 < t1 ? t0 : t1;
    const real b = t0 < t1 ? t1 : t0;
    tn = a > tn ? a : tn;
    tf = b < tf ? b : tf;
  }
  tnear_out = tn;
  return tn <= tf;
}
inline bool ray_box(const Ray& r, const real lo[3], const real hi[3], real tmin, real tmax, real& tnear_out) {
  return slab_box(r.o, r.inv_d, lo, hi, tmin, tmax, tnear_out);
}

/// Local-frame hit of one shape: distance and outward surface normal (unit, local frame).
struct LocalHit {
  real t;
  real n[3];
};

/// Box centred at the origin with half extents h. Rays starting inside hit the exit face.
bool intersect_box(const real o[3], const real d[3], const real h[3], real tmin, real tmax, LocalHit& hit);
/// Sphere of radius r centred at the origin.
bool intersect_sphere(const real o[3], const real d[3], real radius, real tmin, real tmax, LocalHit& hit);
/// Cylinder of radius r along local z, |z| <= half_length, with flat caps.
bool intersect_cylinder(const real o[3], const real d[3], real radius, real half_length, real tmin, real tmax,
                        LocalHit& hit);
/// Capsule: segment from (0,0,-half_length) to (0,0,+half_length) swept by radius r.
bool intersect_capsule(const real o[3], const real d[3], real radius, real half_length, real tmin, real tmax,
                       LocalHit& hit);
/// Plane z = 0 (both sides), normal +z.
bool intersect_plane(const real o[3], const real d[3], real tmin, real tmax, LocalHit& hit);

/// Möller–Trumbore. On a hit within [tmin, tmax] writes t and returns true. The normal is not
/// computed here (only the winning triangle's normal is ever needed).
inline bool intersect_triangle(const real o[3], const real d[3], const real v0[3], const real v1[3], const real v2[3],
                               real tmin, real tmax, real& t_out) {
  const real e1[3] = {v1[0] - v0[0], v1[1] - v0[1], v1[2] - v0[2]};
  const real e2[3] = {v2[0] - v0[0], v2[1] - v0[1], v2[2] - v0[2]};
  const real p[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
  const real det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
  if (std::fabs(det) < 1e-12_r) return false;  // parallel (or degenerate triangle)
  const real inv = 1 / det;
  const real s[3] = {o[0] - v0[0], o[1] - v0[1], o[2] - v0[2]};
  const real u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) * inv;
  if (u < 0 || u > 1) return false;
  const real q[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
  const real v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inv;
  if (v < 0 || u + v > 1) return false;
  const real t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inv;
  if (t < tmin || t > tmax) return false;
  t_out = t;
  return true;
}

/// Unit normal of triangle (v0, v1, v2) (right-hand winding).
void triangle_normal(const real v0[3], const real v1[3], const real v2[3], real n[3]);

}  // namespace kestrel::sensors
