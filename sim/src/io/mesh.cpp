#include "kestrel/sim/mesh.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <unordered_map>

#include "kestrel/sim/limits.hpp"

namespace kestrel::sim {

namespace {

bool fail(std::string& error, const std::string& path, const std::string& msg) {
  error = path + ": " + msg;
  return false;
}

float read_f32(const unsigned char* p) {
  float f;
  std::memcpy(&f, p, 4);  // STL is little-endian, as every host this harness runs on
  return f;
}

/// STL triangles are a soup: vertices are shared by exact coordinate equality (operator==: -0 and
/// +0 are one vertex, a NaN coordinate never matches). A hash map on the coordinate bits replaces
/// the linear search, which made loading quadratic (fuzz F8: 40k triangles took 9 s). Vertices are
/// numbered in order of first appearance, as before, so meshes and results are unchanged.
class VertexWelder {
 public:
  explicit VertexWelder(TriangleMesh& m) : m_(m) {}
  void reserve(std::size_t n) { map_.reserve(n); }
  int index(const Vec3& v) {
    if (!(v[0] == v[0] && v[1] == v[1] && v[2] == v[2])) return push(v);  // NaN: equal to nothing
    const Key k{{v[0], v[1], v[2]}};
    const auto it = map_.find(k);
    if (it != map_.end()) return it->second;
    const int i = push(v);
    map_.emplace(k, i);
    return i;
  }

 private:
  struct Key {
    real c[3];
    bool operator==(const Key& o) const { return c[0] == o.c[0] && c[1] == o.c[1] && c[2] == o.c[2]; }
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = 1469598103934665603ull;  // FNV-1a over the bits, -0 folded into +0 (they compare equal)
      for (real c : k.c) {
        const real z = c == 0 ? real(0) : c;
        unsigned char b[sizeof(real)];
        std::memcpy(b, &z, sizeof(real));
        for (unsigned char x : b) h = (h ^ x) * 1099511628211ull;
      }
      return static_cast<std::size_t>(h);
    }
  };
  int push(const Vec3& v) {
    m_.vertices.push_back(v);
    return static_cast<int>(m_.vertices.size() - 1);
  }
  TriangleMesh& m_;
  std::unordered_map<Key, int, KeyHash> map_;
};

bool load_stl(const std::string& path, const std::string& bytes, TriangleMesh& m, std::string& error) {
  if (bytes.size() >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, bytes.data() + 80, 4);
    if (bytes.size() == 84 + 50 * static_cast<std::size_t>(n)) {
      VertexWelder weld(m);
      weld.reserve(static_cast<std::size_t>(n) * 3);
      const unsigned char* p = reinterpret_cast<const unsigned char*>(bytes.data()) + 84;
      for (std::uint32_t t = 0; t < n; ++t, p += 50) {
        std::array<int, 3> tri{};
        for (int k = 0; k < 3; ++k) {
          const unsigned char* q = p + 12 + 12 * k;  // skip the facet normal
          tri[k] = weld.index(Vec3(read_f32(q), read_f32(q + 4), read_f32(q + 8)));
        }
        m.triangles.push_back(tri);
      }
      return true;
    }
  }
  // ASCII: collect `vertex` lines in threes.
  VertexWelder weld(m);
  std::istringstream in(bytes);
  std::string word;
  std::array<int, 3> tri{};
  int k = 0;
  while (in >> word) {
    if (word != "vertex") continue;
    double x, y, z;
    if (!(in >> x >> y >> z)) return fail(error, path, "ASCII STL: malformed vertex line");
    tri[k++] = weld.index(Vec3(static_cast<real>(x), static_cast<real>(y), static_cast<real>(z)));
    if (k == 3) {
      m.triangles.push_back(tri);
      k = 0;
    }
  }
  if (k != 0) return fail(error, path, "ASCII STL: vertex count is not a multiple of 3");
  return true;
}

bool load_obj(const std::string& path, const std::string& text, TriangleMesh& m, std::string& error) {
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    std::istringstream ls(line);
    std::string tag;
    if (!(ls >> tag)) continue;
    if (tag == "v") {
      double x, y, z;
      if (!(ls >> x >> y >> z)) return fail(error, path, "line " + std::to_string(line_no) + ": expected `v x y z`");
      m.vertices.push_back(Vec3(static_cast<real>(x), static_cast<real>(y), static_cast<real>(z)));
    } else if (tag == "f") {
      std::vector<int> idx;
      std::string ref;
      while (ls >> ref) {
        const long v = std::strtol(ref.c_str(), nullptr, 10);  // "a/b/c": the vertex is the first field
        const long n = static_cast<long>(m.vertices.size());
        const long i = v > 0 ? v - 1 : n + v;
        if (v == 0 || i < 0 || i >= n)
          return fail(error, path, "line " + std::to_string(line_no) + ": face index " + ref + " out of range");
        idx.push_back(static_cast<int>(i));
      }
      if (idx.size() < 3) return fail(error, path, "line " + std::to_string(line_no) + ": a face needs 3 vertices");
      for (std::size_t k = 1; k + 1 < idx.size(); ++k) m.triangles.push_back({idx[0], idx[k], idx[k + 1]});
    }
  }
  return true;
}

}  // namespace

bool load_mesh(const std::string& path, TriangleMesh& out, std::string& error) {
  std::string ext = path.substr(path.find_last_of('.') == std::string::npos ? path.size() : path.find_last_of('.'));
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext != ".stl" && ext != ".obj") return fail(error, path, "unknown mesh format (expected .stl or .obj)");
  std::ifstream f(path, std::ios::binary);
  if (!f) return fail(error, path, "cannot open file");
  const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  TriangleMesh m;
  if (!(ext == ".stl" ? load_stl(path, bytes, m, error) : load_obj(path, bytes, m, error))) return false;
  if (m.triangles.empty()) return fail(error, path, "no triangles");
  // Bounded, not only finite (fuzz F3): a hull ~5e22 m long made libccd's MPR loop forever, and
  // coordinates of ~1e9 m overflowed the trajectory plot. |x|, |y|, |z| <= kMaxMeshCoordinateM.
  for (std::size_t i = 0; i < m.vertices.size(); ++i) {
    const Vec3& v = m.vertices[i];
    for (int k = 0; k < 3; ++k) {
      if (std::isfinite(v[k]) && std::fabs(static_cast<double>(v[k])) <= kMaxMeshCoordinateM) continue;
      std::ostringstream s;
      s << "vertex " << i + 1 << " coordinate " << "xyz"[k] << " = " << static_cast<double>(v[k])
        << " is out of range; allowed: a finite value with |" << "xyz"[k] << "| <= " << kMaxMeshCoordinateM
        << " m (kMaxMeshCoordinateM, sim/limits.hpp)";
      return fail(error, path, s.str());
    }
  }
  out = std::move(m);
  return true;
}

}  // namespace kestrel::sim
