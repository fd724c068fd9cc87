// Triangle meshes from OBJ and STL files, loaded at set-up (never in a step).
//
// Formats: STL binary (80-byte header, uint32 count, 50 bytes per triangle) and ASCII
// ("solid ... facet normal ... vertex x y z ..."), told apart by whether the file size equals
// 84 + 50 * count (an ASCII file may also start with "solid", so the keyword alone is not enough);
// Wavefront OBJ `v x y z` and `f a b c ...` lines (polygons fan-triangulated, negative indices
// relative, `a/b/c` texture/normal references ignored, everything else skipped).
//
// Collision: a mesh obstacle collides as the convex hull of its vertices (ShapeType::convex_hull:
// the support point is the vertex furthest along the direction, fed to libccd's MPR like the other
// non-analytic pairs). Concave meshes are therefore filled in; split a concave object into convex
// parts (one file each) where that matters.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "kestrel/kernel/types.hpp"

namespace kestrel::sim {

struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
};

/// Loads .stl or .obj (by extension, case-insensitive). False with a message naming the file and
/// the problem (unreadable, truncated, bad index, no triangles); `out` untouched then.
[[nodiscard]] bool load_mesh(const std::string& path, TriangleMesh& out, std::string& error);

}  // namespace kestrel::sim
