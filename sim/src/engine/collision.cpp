#include "kestrel/sim/collision.hpp"

#include <ccd/ccd.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>

#include "kestrel/kernel/quaternion.hpp"

namespace kestrel::sim {

Shape make_shape(const ShapeSpec& spec, const Vec3& position_w, const Quat& orientation_wb) {
  Shape s;
  s.type = spec.type;
  s.radius_m = spec.radius_m;
  s.half_length_m = spec.half_length_m;
  s.half_extents_m = spec.half_extents_m;
  s.position_w = position_w;
  s.orientation_wb = orientation_wb;
  return s;
}

void shape_aabb(const Shape& s, Vec3& min_w, Vec3& max_w) {
  Vec3 half;
  if (s.type == ShapeType::sphere) {
    half = Vec3::Constant(s.radius_m);
  } else {
    const Mat3 r = rotation_matrix(s.orientation_wb);
    if (s.type == ShapeType::convex_hull) {
      Vec3 mn = Vec3::Constant(1e30_r), mx = Vec3::Constant(-1e30_r);
      for (int i = 0; i < s.num_vertices; ++i) {
        const Vec3 v = r * s.vertices[i];
        mn = mn.cwiseMin(v);
        mx = mx.cwiseMax(v);
      }
      min_w = s.position_w + mn;
      max_w = s.position_w + mx;
      return;
    }
    if (s.type == ShapeType::box) {
      half = r.cwiseAbs() * s.half_extents_m;
    } else {
      // Segment of half length h along the local z axis, swept by the radius. For a cylinder the
      // radius disc adds r * sqrt(1 - a_i^2) per axis; r is an upper bound of it (conservative).
      half = r.col(2).cwiseAbs() * s.half_length_m + Vec3::Constant(s.radius_m);
    }
  }
  min_w = s.position_w - half;
  max_w = s.position_w + half;
}

namespace {

real sgn(real v) { return v >= 0 ? 1_r : -1_r; }

Vec3 support_local(const Shape& s, const Vec3& d) {
  const real n = d.norm();
  const Vec3 u = n > 0 ? Vec3(d / n) : Vec3(Vec3::UnitZ());
  switch (s.type) {
    case ShapeType::sphere:
      return s.radius_m * u;
    case ShapeType::box:
      return Vec3(sgn(d[0]) * s.half_extents_m[0], sgn(d[1]) * s.half_extents_m[1], sgn(d[2]) * s.half_extents_m[2]);
    case ShapeType::capsule:
      return Vec3(0, 0, sgn(d[2]) * s.half_length_m) + s.radius_m * u;
    case ShapeType::cylinder: {
      const real rxy = std::sqrt(d[0] * d[0] + d[1] * d[1]);
      const Vec3 radial = rxy > 0 ? Vec3(s.radius_m * d[0] / rxy, s.radius_m * d[1] / rxy, 0) : Vec3(Vec3::Zero());
      return radial + Vec3(0, 0, sgn(d[2]) * s.half_length_m);
    }
    case ShapeType::convex_hull: {
      // Furthest vertex; ties keep the lowest index (deterministic).
      int best = 0;
      real best_dot = s.num_vertices > 0 ? s.vertices[0].dot(d) : 0_r;
      for (int i = 1; i < s.num_vertices; ++i) {
        const real p = s.vertices[i].dot(d);
        if (p > best_dot) {
          best_dot = p;
          best = i;
        }
      }
      return s.num_vertices > 0 ? s.vertices[best] : Vec3(Vec3::Zero());
    }
  }
  return Vec3::Zero();
}

Contact no_contact() { return Contact(); }

/// Sphere (centre c, radius r) against a closest point q on B with B-inside flag handled by caller.
Contact sphere_vs_point(const Vec3& c, real r, const Vec3& q) {
  Contact k;
  const Vec3 d = c - q;
  const real dist = d.norm();
  if (dist >= r) return k;
  k.hit = true;
  k.depth_m = r - dist;
  k.normal_w = dist > 0 ? Vec3(d / dist) : Vec3(Vec3::UnitZ());
  k.point_w = q;
  return k;
}

Contact sphere_box(const Vec3& c, real r, const Shape& box) {
  const Vec3 cl = rotate_inverse(box.orientation_wb, c - box.position_w);
  const Vec3& h = box.half_extents_m;
  const Vec3 q = cl.cwiseMax(-h).cwiseMin(h);
  if (q != cl) {
    Contact k = sphere_vs_point(cl, r, q);
    if (!k.hit) return k;
    k.normal_w = rotate(box.orientation_wb, k.normal_w);
    k.point_w = box.position_w + rotate(box.orientation_wb, q);
    return k;
  }
  // Centre inside the box: push out through the nearest face (ties broken by axis order).
  int axis = 0;
  real best = h[0] - std::fabs(cl[0]);
  for (int i = 1; i < 3; ++i) {
    const real f = h[i] - std::fabs(cl[i]);
    if (f < best) {
      best = f;
      axis = i;
    }
  }
  Contact k;
  k.hit = true;
  k.depth_m = best + r;
  Vec3 n = Vec3::Zero();
  n[axis] = sgn(cl[axis]);
  Vec3 p = cl;
  p[axis] = sgn(cl[axis]) * h[axis];
  k.normal_w = rotate(box.orientation_wb, n);
  k.point_w = box.position_w + rotate(box.orientation_wb, p);
  return k;
}

/// Closest point to p on segment [a, b].
Vec3 closest_on_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const real l2 = ab.squaredNorm();
  real t = l2 > 0 ? (p - a).dot(ab) / l2 : 0_r;
  t = std::min(1_r, std::max(0_r, t));
  return a + t * ab;
}

void capsule_segment(const Shape& s, Vec3& a, Vec3& b) {
  const Vec3 axis = rotate(s.orientation_wb, Vec3(0, 0, s.half_length_m));
  a = s.position_w - axis;
  b = s.position_w + axis;
}

Contact sphere_capsule(const Vec3& c, real r, const Shape& cap) {
  Vec3 a, b;
  capsule_segment(cap, a, b);
  const Vec3 q = closest_on_segment(c, a, b);
  Contact k = sphere_vs_point(c, r + cap.radius_m, q);
  if (!k.hit) return k;
  k.point_w = q + cap.radius_m * k.normal_w;
  return k;
}

Contact sphere_cylinder(const Vec3& c, real r, const Shape& cyl) {
  const Vec3 cl = rotate_inverse(cyl.orientation_wb, c - cyl.position_w);
  const real rxy = std::sqrt(cl[0] * cl[0] + cl[1] * cl[1]);
  const real h = cyl.half_length_m;
  const bool inside = rxy <= cyl.radius_m && std::fabs(cl[2]) <= h;
  if (!inside) {
    Vec3 q = cl;
    if (rxy > cyl.radius_m) {
      q[0] = cl[0] * cyl.radius_m / rxy;
      q[1] = cl[1] * cyl.radius_m / rxy;
    }
    q[2] = std::min(h, std::max(-h, cl[2]));
    Contact k = sphere_vs_point(cl, r, q);
    if (!k.hit) return k;
    k.normal_w = rotate(cyl.orientation_wb, k.normal_w);
    k.point_w = cyl.position_w + rotate(cyl.orientation_wb, q);
    return k;
  }
  Contact k;
  k.hit = true;
  const real side = cyl.radius_m - rxy;
  const real cap = h - std::fabs(cl[2]);
  Vec3 n, p;
  if (cap <= side || rxy == 0) {
    n = Vec3(0, 0, sgn(cl[2]));
    p = Vec3(cl[0], cl[1], sgn(cl[2]) * h);
    k.depth_m = cap + r;
  } else {
    n = Vec3(cl[0] / rxy, cl[1] / rxy, 0);
    p = Vec3(n[0] * cyl.radius_m, n[1] * cyl.radius_m, cl[2]);
    k.depth_m = side + r;
  }
  k.normal_w = rotate(cyl.orientation_wb, n);
  k.point_w = cyl.position_w + rotate(cyl.orientation_wb, p);
  return k;
}

/// Closest points of segments [p1, q1] and [p2, q2] (Ericson 2005, ClosestPtSegmentSegment).
void closest_segments(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2, Vec3& c1, Vec3& c2) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const real a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  real s = 0, t = 0;
  const real eps = 1e-12_r;
  if (a <= eps && e <= eps) {
    s = t = 0;
  } else if (a <= eps) {
    t = std::min(1_r, std::max(0_r, f / e));
  } else {
    const real c = d1.dot(r);
    if (e <= eps) {
      s = std::min(1_r, std::max(0_r, -c / a));
    } else {
      const real b = d1.dot(d2), denom = a * e - b * b;
      s = denom > eps ? std::min(1_r, std::max(0_r, (b * f - c * e) / denom)) : 0_r;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::min(1_r, std::max(0_r, -c / a));
      } else if (t > 1) {
        t = 1;
        s = std::min(1_r, std::max(0_r, (b - c) / a));
      }
    }
  }
  c1 = p1 + d1 * s;
  c2 = p2 + d2 * t;
}

Contact capsule_capsule(const Shape& a, const Shape& b) {
  Vec3 a0, a1, b0, b1, ca, cb;
  capsule_segment(a, a0, a1);
  capsule_segment(b, b0, b1);
  closest_segments(a0, a1, b0, b1, ca, cb);
  Contact k = sphere_vs_point(ca, a.radius_m + b.radius_m, cb);
  if (!k.hit) return k;
  k.point_w = cb + b.radius_m * k.normal_w;
  return k;
}

// libccd glue: shapes are passed by pointer; libccd is built with double (ccd/config.h).
//
// The guard: libccd's MPR (mpr.c) runs its portal discovery and refinement as `while` loops that
// do not read ccd.max_iterations (only GJK does), and with a hull ~1e22 m long next to a 0.2 m
// robot they never ended (fuzz F3). Mesh coordinates are now bounded at load (kMaxMeshCoordinateM),
// and as a second line every MPR call gets a budget of support-function calls: past it the
// support callback longjmps back to guarded_mpr, which reports "no contact". A normal call needs a
// few dozen; the budget never binds in the shipped scenarios (the golden hash is unchanged). The
// jump crosses only libccd's C frames and ccd_support, whose locals are trivially destructible.
constexpr int kMaxMprSupportCalls = 2000;
struct MprBudget {
  int calls = 0;
  std::jmp_buf exhausted;
};
struct MprShape {
  const Shape* shape;
  MprBudget* budget;
};
void ccd_support(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const MprShape& m = *static_cast<const MprShape*>(obj);
  if (++m.budget->calls > kMaxMprSupportCalls) std::longjmp(m.budget->exhausted, 1);
  const Vec3 d(static_cast<real>(dir->v[0]), static_cast<real>(dir->v[1]), static_cast<real>(dir->v[2]));
  const Vec3 p = support_point(*m.shape, d);
  for (int i = 0; i < 3; ++i) out->v[i] = static_cast<ccd_real_t>(p[i]);
}
void ccd_center(const void* obj, ccd_vec3_t* out) {
  const Shape& s = *static_cast<const MprShape*>(obj)->shape;
  for (int i = 0; i < 3; ++i) out->v[i] = static_cast<ccd_real_t>(s.position_w[i]);
}
// Only pointers live across the setjmp (nothing here is modified after it), so no local can be
// clobbered by the longjmp. Returns -2 when the budget ran out.
int guarded_mpr(const MprShape* a, const MprShape* b, const ccd_t* ccd, ccd_real_t* depth, ccd_vec3_t* dir, ccd_vec3_t* pos) {
  if (setjmp(a->budget->exhausted) != 0) return -2;
  return ccdMPRPenetration(a, b, ccd, depth, dir, pos);
}

Contact collide_mpr(const Shape& a, const Shape& b) {
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = ccd_support;
  ccd.support2 = ccd_support;
  ccd.center1 = ccd_center;
  ccd.center2 = ccd_center;
  ccd.max_iterations = 100;
  ccd.mpr_tolerance = 1e-6;
  ccd_real_t depth = 0;
  ccd_vec3_t dir, pos;
  Contact k;
  MprBudget budget;
  const MprShape ma{&a, &budget}, mb{&b, &budget};
  if (guarded_mpr(&ma, &mb, &ccd, &depth, &dir, &pos) != 0) return k;
  k.hit = true;
  k.depth_m = static_cast<real>(depth);
  // libccd's dir is the direction B must move to separate (from A towards B); ours points into A.
  k.normal_w = -Vec3(static_cast<real>(dir.v[0]), static_cast<real>(dir.v[1]), static_cast<real>(dir.v[2]));
  k.point_w = Vec3(static_cast<real>(pos.v[0]), static_cast<real>(pos.v[1]), static_cast<real>(pos.v[2]));
  return k;
}

Contact flip(Contact k) {
  k.normal_w = -k.normal_w;
  return k;
}

}  // namespace

Vec3 support_point(const Shape& s, const Vec3& dir_w) {
  const Vec3 dl = rotate_inverse(s.orientation_wb, dir_w);
  return s.position_w + rotate(s.orientation_wb, support_local(s, dl));
}

Contact collide_plane(const Shape& a, real plane_z_m) {
  Contact k;
  // A sphere's lowest point needs no rotation (the default robot shape: this runs every physics
  // step of every robot, so the general support-point path with two rotations is skipped).
  const Vec3 low = a.type == ShapeType::sphere ? Vec3(a.position_w - Vec3(0, 0, a.radius_m))
                                               : support_point(a, Vec3(0, 0, -1));
  if (low[2] >= plane_z_m) return k;
  k.hit = true;
  k.depth_m = plane_z_m - low[2];
  k.normal_w = Vec3::UnitZ();
  k.point_w = Vec3(low[0], low[1], plane_z_m);
  return k;
}

Contact collide(const Shape& a, const Shape& b) {
  if (a.type == ShapeType::sphere) {
    switch (b.type) {
      case ShapeType::sphere:
        return sphere_vs_point(a.position_w, a.radius_m + b.radius_m, b.position_w).hit
                   ? [&] {
                       Contact k = sphere_vs_point(a.position_w, a.radius_m + b.radius_m, b.position_w);
                       k.point_w = b.position_w + b.radius_m * k.normal_w;
                       return k;
                     }()
                   : no_contact();
      case ShapeType::box:
        return sphere_box(a.position_w, a.radius_m, b);
      case ShapeType::capsule:
        return sphere_capsule(a.position_w, a.radius_m, b);
      case ShapeType::cylinder:
        return sphere_cylinder(a.position_w, a.radius_m, b);
      case ShapeType::convex_hull:
        break;  // MPR below
    }
  }
  if (b.type == ShapeType::sphere && a.type != ShapeType::convex_hull) return flip(collide(b, a));
  if (a.type == ShapeType::capsule && b.type == ShapeType::capsule) return capsule_capsule(a, b);
  return collide_mpr(a, b);
}

}  // namespace kestrel::sim
