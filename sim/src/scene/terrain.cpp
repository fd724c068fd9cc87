// Terrain: generators, heightmap files, surface height and robot-terrain contact (see terrain.hpp).
#include "kestrel/sim/terrain.hpp"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/limits.hpp"
#include "kestrel/sim/mesh.hpp"

namespace kestrel::sim {

namespace {

/// The pixel-count refusal of both loaders (checked from the header, before any allocation).
std::string too_many_samples(const std::string& path, long long w, long long h) {
  return "\"" + path + "\": " + std::to_string(w) + " x " + std::to_string(h) + " = " + std::to_string(w * h) +
         " samples; allowed: width, height >= 2 and width x height <= " + std::to_string(kMaxHeightmapSamples) +
         " (kMaxHeightmapSamples, sim/limits.hpp)";
}

std::string where(const TerrainConfig& c, const std::string& field) {
  return (c.source_file.empty() ? std::string() : c.source_file + ": ") + "env.terrain." + field + ": ";
}

// ---- heightmap images -------------------------------------------------------------------------

/// Netpbm graymap: P5 (binary, 1 or 2 big-endian bytes per sample) or P2 (ASCII). Comments (#)
/// are allowed between header fields.
bool read_pgm(const std::string& path, int& w, int& h, std::vector<double>& px, std::string& msg) {
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    msg = "cannot open \"" + path + "\"";
    return false;
  }
  const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  std::size_t pos = 0;
  auto token = [&](std::string& out) {
    out.clear();
    for (;;) {
      while (pos < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[pos]))) ++pos;
      if (pos < bytes.size() && bytes[pos] == '#') {
        while (pos < bytes.size() && bytes[pos] != '\n') ++pos;
        continue;
      }
      break;
    }
    while (pos < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[pos]))) out += bytes[pos++];
    return !out.empty();
  };
  std::string magic, sw, sh, smax;
  if (!token(magic) || (magic != "P5" && magic != "P2") || !token(sw) || !token(sh) || !token(smax)) {
    msg = "\"" + path + "\" is not a PGM graymap (expected a P5 or P2 header)";
    return false;
  }
  // strtoll, not atoi: an out-of-int value must be refused, not wrapped. Everything about the
  // header is checked before the pixel buffer is allocated (fuzz F4: a 19-byte file asked for 17 GB).
  const long long lw = std::strtoll(sw.c_str(), nullptr, 10), lh = std::strtoll(sh.c_str(), nullptr, 10);
  const long long maxval = std::strtoll(smax.c_str(), nullptr, 10);
  if (lw < 2 || lh < 2 || maxval < 1 || maxval > 65535) {
    msg = "\"" + path + "\": expected width and height >= 2 and 1 <= maxval <= 65535";
    return false;
  }
  if (lw > kMaxHeightmapSamples || lh > kMaxHeightmapSamples || lw * lh > kMaxHeightmapSamples) {
    msg = too_many_samples(path, lw, lh);
    return false;
  }
  w = static_cast<int>(lw);
  h = static_cast<int>(lh);
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  const std::size_t left = bytes.size() > pos ? bytes.size() - pos : 0;
  // P2: every sample is at least one digit, and all but the last are followed by whitespace.
  // P5: exactly n samples of 1 or 2 bytes after the single whitespace that ends the header.
  const std::size_t need = magic == "P2" ? 2 * n - 1 : 1 + n * (maxval > 255 ? 2 : 1);
  if (left < need) {
    msg = "\"" + path + "\": truncated pixel data (" + std::to_string(w) + " x " + std::to_string(h) + " samples need at least " +
          std::to_string(need) + " bytes after the header, the file has " + std::to_string(left) + ")";
    return false;
  }
  px.assign(n, 0);
  if (magic == "P2") {
    std::string t;
    for (std::size_t i = 0; i < n; ++i) {
      if (!token(t)) {
        msg = "\"" + path + "\": truncated pixel data";
        return false;
      }
      px[i] = std::atof(t.c_str());
    }
    return true;
  }
  ++pos;  // the single whitespace after maxval
  const std::size_t bpp = maxval > 255 ? 2 : 1;
  if (bytes.size() < pos + n * bpp) {
    msg = "\"" + path + "\": truncated pixel data";
    return false;
  }
  const unsigned char* p = reinterpret_cast<const unsigned char*>(bytes.data()) + pos;
  for (std::size_t i = 0; i < n; ++i) px[i] = bpp == 2 ? 256.0 * p[2 * i] + p[2 * i + 1] : p[i];
  return true;
}

/// Grayscale PNG (1-16 bit) through libpng's classic API; colour images are refused rather than
/// converted (a heightmap's channel would be a guess).
bool read_png(const std::string& path, int& w, int& h, std::vector<double>& px, std::string& msg) {
  FILE* fp = std::fopen(path.c_str(), "rb");
  if (fp == nullptr) {
    msg = "cannot open \"" + path + "\"";
    return false;
  }
  // The file size bounds what its image data can hold: deflate expands at most ~1032:1.
  std::fseek(fp, 0, SEEK_END);
  const long file_bytes = std::ftell(fp);
  std::fseek(fp, 0, SEEK_SET);
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  std::vector<unsigned char> data;
  std::vector<png_bytep> rows;
  bool ok = false;
  if (png != nullptr && info != nullptr && setjmp(png_jmpbuf(png)) == 0) {
    png_init_io(png, fp);
    png_read_info(png, info);
    const int ct = png_get_color_type(png, info), depth = png_get_bit_depth(png, info);
    // libpng accepts up to 1e6 x 1e6 (fuzz F4: a 68-byte file asked for 1 TB): the sample count
    // and the data the file can hold are checked from the header, before allocating.
    const long long lw = static_cast<long long>(png_get_image_width(png, info));
    const long long lh = static_cast<long long>(png_get_image_height(png, info));
    const long long channels = (ct & PNG_COLOR_MASK_ALPHA) != 0 ? 2 : 1;
    const long long raw_bytes = lh * (1 + (lw * depth * channels + 7) / 8);  // a filter byte per row
    w = static_cast<int>(std::min<long long>(lw, 1 << 30));
    h = static_cast<int>(std::min<long long>(lh, 1 << 30));
    if ((ct & PNG_COLOR_MASK_COLOR) != 0 || (ct & PNG_COLOR_MASK_PALETTE) != 0) {
      msg = "\"" + path + "\": expected a grayscale PNG (colour type " + std::to_string(ct) + ")";
    } else if (lw < 2 || lh < 2) {
      msg = "\"" + path + "\": expected width and height >= 2";
    } else if (lw * lh > kMaxHeightmapSamples) {
      msg = too_many_samples(path, lw, lh);
    } else if (static_cast<double>(raw_bytes) > 1032.0 * static_cast<double>(file_bytes) + 1024.0) {
      msg = "\"" + path + "\": truncated image data (" + std::to_string(lw) + " x " + std::to_string(lh) + " at " +
            std::to_string(depth) + " bits is " + std::to_string(raw_bytes) + " bytes, more than a " + std::to_string(file_bytes) +
            "-byte file can hold)";
    } else {
      if (depth < 8) png_set_expand_gray_1_2_4_to_8(png);
      if ((ct & PNG_COLOR_MASK_ALPHA) != 0) png_set_strip_alpha(png);
      png_read_update_info(png, info);
      const std::size_t stride = png_get_rowbytes(png, info);
      data.assign(stride * static_cast<std::size_t>(h), 0);
      rows.resize(static_cast<std::size_t>(h));
      for (int r = 0; r < h; ++r) rows[static_cast<std::size_t>(r)] = data.data() + stride * static_cast<std::size_t>(r);
      png_read_image(png, rows.data());
      const bool two = depth == 16;
      px.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), 0);
      for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) {
          const unsigned char* p = rows[static_cast<std::size_t>(r)] + (two ? 2 : 1) * c;
          px[static_cast<std::size_t>(r) * w + c] = two ? 256.0 * p[0] + p[1] : p[0];
        }
      ok = true;
    }
  } else if (msg.empty()) {
    msg = "\"" + path + "\": not a readable PNG file";
  }
  png_destroy_read_struct(png ? &png : nullptr, info ? &info : nullptr, nullptr);
  std::fclose(fp);
  return ok;
}

// ---- geometry -----------------------------------------------------------------------------------

/// Closest point on triangle abc to p (Ericson 2005, ClosestPtPointTriangle, Voronoi regions).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const real d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const real d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const real vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const real d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const real vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const real va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const real denom = 1 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

/// q (on the plane of abc) inside the triangle, with a relative tolerance so shared edges count.
bool inside_triangle(const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n) {
  const real eps = -1e-6_r * (b - a).cross(c - a).norm();
  return n.dot((b - a).cross(q - a)) >= eps && n.dot((c - b).cross(q - b)) >= eps && n.dot((a - c).cross(q - c)) >= eps;
}

/// One-sided triangle (outward = right-hand winding) against a posed shape; solid behind the face
/// up to back_limit_m.
bool triangle_contact(const Shape& s, const Vec3& a, const Vec3& b, const Vec3& c, real back_limit_m, Contact& k) {
  Vec3 n = (b - a).cross(c - a);
  const real len = n.norm();
  if (!(len > 0)) return false;
  n /= len;
  if (s.type == ShapeType::sphere) {
    const Vec3& o = s.position_w;
    const real d = n.dot(o - a);
    if (d >= 0) {
      const Vec3 q = closest_on_triangle(o, a, b, c);
      const Vec3 dv = o - q;
      const real dist = dv.norm();
      if (dist >= s.radius_m) return false;
      k.hit = true;
      k.depth_m = s.radius_m - dist;
      k.normal_w = dist > 1e-9_r ? Vec3(dv / dist) : n;
      k.point_w = q;
      return true;
    }
    if (-d > back_limit_m) return false;
    const Vec3 q = o - d * n;
    if (!inside_triangle(q, a, b, c, n)) return false;
    k.hit = true;
    k.depth_m = s.radius_m - d;
    k.normal_w = n;
    k.point_w = q;
    return true;
  }
  const Vec3 p = support_point(s, -n);
  const real depth = n.dot(a - p);
  if (!(depth > 0) || depth > back_limit_m) return false;
  const Vec3 q = p + depth * n;
  if (!inside_triangle(q, a, b, c, n)) return false;
  k.hit = true;
  k.depth_m = depth;
  k.normal_w = n;
  k.point_w = q;
  return true;
}

/// Adds k to the contact set, merging with a contact of nearly the same normal (the deeper wins;
/// equal depth keeps the earlier, so the visit order decides deterministically).
void merge_contact(const Contact& k, Contact* out, int& count) {
  constexpr real kSameNormalCos = 0.95_r;
  int best = -1;
  real best_dot = -2;
  for (int i = 0; i < count; ++i) {
    const real d = out[i].normal_w.dot(k.normal_w);
    if (d > best_dot) {
      best_dot = d;
      best = i;
    }
  }
  if (best >= 0 && (best_dot >= kSameNormalCos || count == kMaxTerrainContacts)) {
    if (k.depth_m > out[best].depth_m) out[best] = k;
    return;
  }
  out[count++] = k;
}


// A rectangle of a height array: samples [i0, i0 + w) along x by [j0, j0 + l) along y of a grid nx
// samples wide, spacing hs. The generators below write one tile (the whole grid is one tile).
struct Tile {
  real* h;
  int nx, i0, j0, w, l;
  real hs;
  real& at(int i, int j) const { return h[static_cast<std::size_t>(j0 + j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i0 + i)]; }
};

// terrain_utils.pyramid_sloped_terrain: max_height * xx * yy with xx, yy the normalised distances
// from the border (1 at the centre) over an extent ex x ey (m), clipped to the height at the
// platform's edge.
void tile_pyramid_slope(const Tile& t, real ex, real ey, real slope, real platform_m) {
  const real cx = ex / 2, cy = ey / 2, max_h = slope * cx;
  auto raw = [&](real x, real y) { return max_h * ((cx - std::fabs(cx - x)) / cx) * ((cy - std::fabs(cy - y)) / cy); };
  const real edge = raw(cx - platform_m / 2, cy - platform_m / 2);
  const real lo = std::min(edge, 0_r), hi = std::max(edge, 0_r);
  for (int j = 0; j < t.l; ++j)
    for (int i = 0; i < t.w; ++i) t.at(i, j) = std::min(hi, std::max(lo, raw(static_cast<real>(i) * t.hs, static_cast<real>(j) * t.hs)));
}

// terrain_utils.pyramid_stairs_terrain: nested rectangles, each step_width narrower per side and
// step_height higher (negative: a pit of stairs), until the platform remains. Widths in samples.
void tile_pyramid_stairs(const Tile& t, int step_w, int platform, real step_height_m) {
  int x0 = 0, x1 = t.w, y0 = 0, y1 = t.l;
  real height = 0;
  while (x1 - x0 > platform && y1 - y0 > platform) {
    x0 += step_w;
    x1 -= step_w;
    y0 += step_w;
    y1 -= step_w;
    height += step_height_m;
    for (int j = std::max(0, y0); j < std::min(t.l, y1); ++j)
      for (int i = std::max(0, x0); i < std::min(t.w, x1); ++i) t.at(i, j) = height;
  }
}

// terrain_utils.random_uniform_terrain: heights drawn from {min, min + step, ..., max} on a grid of
// `down` spacing over the extent ex x ey, linearly interpolated to the samples; written (add
// false) or added to what the tile holds (add true: legged_gym's rough slope).
void tile_random_uniform(const Tile& t, real ex, real ey, real min_h, real max_h, real step_h, real down, RngStream& rng,
                         bool add) {
  const int levels = static_cast<int>(std::floor((max_h - min_h) / step_h + 1e-4_r)) + 1;
  const int cnx = std::max(2, static_cast<int>(ex / down)), cny = std::max(2, static_cast<int>(ey / down));
  std::vector<real> coarse(static_cast<std::size_t>(cnx) * static_cast<std::size_t>(cny));
  for (real& v : coarse) v = min_h + step_h * static_cast<real>(rng.next_u32() % static_cast<std::uint32_t>(levels));
  for (int j = 0; j < t.l; ++j)
    for (int i = 0; i < t.w; ++i) {
      const real u = static_cast<real>(i) / static_cast<real>(t.w - 1) * static_cast<real>(cnx - 1);
      const real v = static_cast<real>(j) / static_cast<real>(t.l - 1) * static_cast<real>(cny - 1);
      const int ci = std::min(cnx - 2, static_cast<int>(u)), cj = std::min(cny - 2, static_cast<int>(v));
      const real fu = u - static_cast<real>(ci), fv = v - static_cast<real>(cj);
      auto cc = [&](int a, int b) { return coarse[static_cast<std::size_t>(b) * cnx + a]; };
      const real z = (1 - fv) * ((1 - fu) * cc(ci, cj) + fu * cc(ci + 1, cj)) + fv * ((1 - fu) * cc(ci, cj + 1) + fu * cc(ci + 1, cj + 1));
      if (add) {
        t.at(i, j) += z;
      } else {
        t.at(i, j) = z;
      }
    }
}

// terrain_utils.discrete_obstacles_terrain: num_rects rectangles with sides drawn from
// {min, min + 4, ...} < max samples, at corners on a 4-sample lattice, each raised or sunk by one of
// {-h, -h/2, h/2, h}; then the central platform is levelled to 0.
void tile_discrete_obstacles(const Tile& t, real height_m, int min_size, int max_size, int num_rects, int platform, RngStream& rng) {
  const real heights[4] = {-height_m, -height_m / 2, height_m / 2, height_m};
  const auto pick = [&rng](int lo, int hi) {  // one of lo, lo + 4, ... < hi (lo when the range is empty)
    const int count = hi > lo ? (hi - lo + 3) / 4 : 1;
    return lo + 4 * static_cast<int>(rng.next_u32() % static_cast<std::uint32_t>(count));
  };
  for (int r = 0; r < num_rects; ++r) {
    const int sw = pick(min_size, max_size), sl = pick(min_size, max_size);
    const int i0 = pick(0, t.w - sw), j0 = pick(0, t.l - sl);
    const real z = heights[rng.next_u32() % 4u];
    for (int j = j0; j < std::min(t.l, j0 + sl); ++j)
      for (int i = i0; i < std::min(t.w, i0 + sw); ++i) t.at(i, j) = z;
  }
  for (int j = (t.l - platform) / 2; j < (t.l + platform) / 2; ++j)
    for (int i = (t.w - platform) / 2; i < (t.w + platform) / 2; ++i) t.at(i, j) = 0;
}

// legged_gym's make_terrain(choice, difficulty) on one tile (extent ex x ey): the type by the
// cumulative proportions p (smooth slope, rough slope, stairs up, stairs down, discrete
// obstacles; flat past the last), the size of its features by the difficulty in [0, 1].
void make_tile(const Tile& t, real ex, real ey, real choice, real difficulty, const real* p, RngStream& rng) {
  real slope = difficulty * 0.4_r;
  real step_height = 0.05_r + 0.18_r * difficulty;
  const real obstacle_height = 0.05_r + difficulty * 0.2_r;
  const int platform = static_cast<int>(std::floor(3 / t.hs + 1e-4_r));  // 3 m, legged_gym's platform_size
  if (choice < p[0]) {
    if (choice < p[0] / 2) slope = -slope;
    tile_pyramid_slope(t, ex, ey, slope, 3);
  } else if (choice < p[1]) {
    tile_pyramid_slope(t, ex, ey, slope, 3);
    tile_random_uniform(t, ex, ey, -0.05_r, 0.05_r, 0.005_r, 0.2_r, rng, true);
  } else if (choice < p[3]) {
    if (choice < p[2]) step_height = -step_height;  // a pit: the robot climbs up out of it
    tile_pyramid_stairs(t, static_cast<int>(std::floor(0.31_r / t.hs + 1e-4_r)), platform, step_height);
  } else if (choice < p[4]) {
    tile_discrete_obstacles(t, obstacle_height, static_cast<int>(std::floor(1 / t.hs + 1e-4_r)),
                            static_cast<int>(std::floor(2 / t.hs + 1e-4_r)), 20, platform, rng);
  }
}

}  // namespace

const char* terrain_procedural_names() {
  return "flat, slope, pyramid_slope, stairs, pyramid_stairs, random_uniform, wave, curriculum, randomized";
}

bool Terrain::build(const TerrainConfig& config, std::uint64_t seed, std::unique_ptr<Terrain>& out, std::string& error) {
  std::unique_ptr<Terrain> t(new Terrain());
  t->type_ = config.type;
  if (config.type == TerrainType::heightfield && !t->build_heightfield(config, seed, error)) return false;
  if (config.type == TerrainType::trimesh && !t->build_trimesh(config, error)) return false;
  for (real v : config.measured_points_x_m)
    if (!std::isfinite(v)) return error = where(config, "measured_points_x") + "expected finite numbers", false;
  for (real v : config.measured_points_y_m)
    if (!std::isfinite(v)) return error = where(config, "measured_points_y") + "expected finite numbers", false;
  out = std::move(t);
  return true;
}

// Long on purpose: one branch per height source (list, image, each procedural generator), each
// short and validated where it reads its fields; the generators share the grid set-up above them.
bool Terrain::build_heightfield(const TerrainConfig& c, std::uint64_t seed, std::string& error) {
  auto fail = [&](const std::string& field, const std::string& msg) {
    error = where(c, field) + msg;
    return false;
  };
  if (!(c.horizontal_scale_m > 0) || !std::isfinite(c.horizontal_scale_m))
    return fail("horizontal_scale_m", "expected a positive number");
  if (!c.origin_m.allFinite()) return fail("origin_m", "expected finite numbers");
  const real hs = c.horizontal_scale_m;
  const int sources = (c.heights_m.empty() ? 0 : 1) + (c.image_file.empty() ? 0 : 1) + (c.procedural.empty() ? 0 : 1);
  if (sources != 1) return fail("(type heightfield)", "expected exactly one of heights_m, image_file, procedural");
  int nx = 0, ny = 0;
  std::vector<real> h;
  if (!c.heights_m.empty()) {
    nx = c.nx;
    ny = c.ny;
    if (nx < 2 || ny < 2 || c.heights_m.size() != static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny))
      return fail("heights_m", "expected a list of >= 2 rows of >= 2 numbers each, all rows the same length");
    h = c.heights_m;
  } else if (!c.image_file.empty()) {
    if (!(c.vertical_scale_m > 0) || !std::isfinite(c.vertical_scale_m)) return fail("vertical_scale_m", "expected a positive number");
    std::string ext = c.image_file.substr(std::min(c.image_file.size(), c.image_file.find_last_of('.')));
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
    std::vector<double> px;
    std::string msg;
    bool ok = false;
    if (ext == ".pgm") ok = read_pgm(c.image_file, nx, ny, px, msg);
    else if (ext == ".png") ok = read_png(c.image_file, nx, ny, px, msg);
    else msg = "unknown heightmap format \"" + c.image_file + "\" (expected .pgm or .png)";
    if (!ok) return fail("image_file", msg);
    // Image row 0 is the top of the picture: the largest y (a map seen from above, +x right).
    h.assign(px.size(), 0);
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        h[static_cast<std::size_t>(j) * nx + i] = static_cast<real>(px[static_cast<std::size_t>(ny - 1 - j) * nx + i] * c.vertical_scale_m);
  } else {
    const bool tiled = c.procedural == "curriculum" || c.procedural == "randomized";
    int tile_w = 0, tile_l = 0, border = 0;  // samples
    if (tiled) {
      // legged_gym's Terrain: rows of tiles along x (levels), columns along y (types), a border.
      if (!(c.tile_length_m >= 4) || !(c.tile_width_m >= 4))
        return fail("tile_length_m", "expected tile_length_m and tile_width_m >= 4 m (a 3 m platform at each tile's centre)");
      if (c.terrain_proportions.size() != 5) return fail("terrain_proportions", "expected 5 numbers");
      tile_w = static_cast<int>(std::floor(c.tile_length_m / hs + 1e-4_r));
      tile_l = static_cast<int>(std::floor(c.tile_width_m / hs + 1e-4_r));
      border = static_cast<int>(std::floor(c.border_size_m / hs + 1e-4_r));
      nx = c.num_rows * tile_w + 2 * border;
      ny = c.num_cols * tile_l + 2 * border;
    } else {
      if (!(c.length_x_m >= hs) || !(c.width_y_m >= hs)) return fail("length_x_m", "expected length_x_m and width_y_m >= horizontal_scale_m");
      nx = static_cast<int>(std::floor(c.length_x_m / hs + 0.5_r)) + 1;
      ny = static_cast<int>(std::floor(c.width_y_m / hs + 0.5_r)) + 1;
    }
    if (static_cast<long long>(nx) * ny > kMaxHeightmapSamples)
      return fail("length_x_m", "grid of " + std::to_string(static_cast<long long>(nx) * ny) + " samples; allowed: at most " +
                                    std::to_string(kMaxHeightmapSamples) + " (kMaxHeightmapSamples, sim/limits.hpp)");
    const real lx = static_cast<real>(nx - 1) * hs, ly = static_cast<real>(ny - 1) * hs;
    h.assign(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny), 0);
    auto at = [&](int i, int j) -> real& { return h[static_cast<std::size_t>(j) * nx + i]; };
    const Tile whole{h.data(), nx, 0, 0, nx, ny, hs};
    const std::string& p = c.procedural;
    if (tiled) {
      // Cumulative proportions, normalised (legged_gym expects them to sum to 1).
      real cum[5], total = 0;
      for (real v : c.terrain_proportions) total += v;
      real run = 0;
      for (int k = 0; k < 5; ++k) cum[k] = (run += c.terrain_proportions[static_cast<std::size_t>(k)]) / total;
      RngStream rng(seed, 0, kPurposeTerrain);
      tile_rows_ = c.num_rows;
      tile_cols_ = c.num_cols;
      tile_origins_.assign(static_cast<std::size_t>(tile_rows_) * static_cast<std::size_t>(tile_cols_), Vec3::Zero());
      const real ex = static_cast<real>(tile_w) * hs, ey = static_cast<real>(tile_l) * hs;
      static constexpr real kRandomDifficulties[3] = {0.5_r, 0.75_r, 0.9_r};  // randomized_terrain's
      for (int j = 0; j < c.num_cols; ++j)
        for (int i = 0; i < c.num_rows; ++i) {
          real choice, difficulty;
          if (p == "curriculum") {
            difficulty = static_cast<real>(i) / static_cast<real>(c.num_rows);
            choice = static_cast<real>(j) / static_cast<real>(c.num_cols) + 0.001_r;
          } else {
            choice = rng.uniform();
            difficulty = kRandomDifficulties[rng.next_u32() % 3u];
          }
          const Tile t{h.data(), nx, border + i * tile_w, border + j * tile_l, tile_w, tile_l, hs};
          make_tile(t, ex, ey, choice, difficulty, cum, rng);
          // The tile's origin: its centre, at the highest surface of the central 2 m x 2 m (local
          // sample coordinates here; moved into the world below).
          real top = -std::numeric_limits<real>::infinity();
          const int x1 = static_cast<int>((ex / 2 - 1) / hs), x2 = static_cast<int>((ex / 2 + 1) / hs);
          const int y1 = static_cast<int>((ey / 2 - 1) / hs), y2 = static_cast<int>((ey / 2 + 1) / hs);
          for (int b = y1; b < y2; ++b)
            for (int a = x1; a < x2; ++a) top = std::max(top, t.at(a, b));
          tile_origins_[static_cast<std::size_t>(i * c.num_cols + j)] =
              Vec3((static_cast<real>(t.i0) + static_cast<real>(tile_w) / 2) * hs, (static_cast<real>(t.j0) + static_cast<real>(tile_l) / 2) * hs, top);
        }
    } else if (p == "flat") {
    } else if (p == "slope") {
      // terrain_utils.sloped_terrain: rises along x by `slope` per metre.
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) at(i, j) = c.slope * static_cast<real>(i) * hs;
    } else if (p == "pyramid_slope") {
      tile_pyramid_slope(whole, lx, ly, c.slope, c.platform_size_m);
    } else if (p == "stairs") {
      // terrain_utils.stairs_terrain: step k (along x, width step_width_m) at (k + 1) step_height_m.
      if (!(c.step_width_m >= hs)) return fail("step_width_m", "expected a number >= horizontal_scale_m");
      const int w = static_cast<int>(std::floor(c.step_width_m / hs + 1e-4_r));  // 0.3 / 0.1 is 3, not 2.99..
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) at(i, j) = static_cast<real>(i / w + 1) * c.step_height_m;
    } else if (p == "pyramid_stairs") {
      if (!(c.step_width_m >= hs)) return fail("step_width_m", "expected a number >= horizontal_scale_m");
      tile_pyramid_stairs(whole, static_cast<int>(std::floor(c.step_width_m / hs + 1e-4_r)),
                          static_cast<int>(std::floor(c.platform_size_m / hs + 1e-4_r)), c.step_height_m);
    } else if (p == "random_uniform") {
      // terrain_utils.random_uniform_terrain: heights drawn from {min, min + step, ..., max} on a
      // grid of downsampled_scale_m spacing, linearly interpolated to the samples.
      if (!(c.height_step_m > 0) || !(c.max_height_m >= c.min_height_m))
        return fail("height_step_m", "expected height_step_m > 0 and max_height_m >= min_height_m");
      if (!(c.downsampled_scale_m > 0)) return fail("downsampled_scale_m", "expected a positive number");
      RngStream rng(seed, 0, kPurposeTerrain);
      tile_random_uniform(whole, lx, ly, c.min_height_m, c.max_height_m, c.height_step_m, c.downsampled_scale_m, rng, false);
    } else if (p == "wave") {
      // terrain_utils.wave_terrain: amplitude (cos(y / div) + sin(x / div)), num_waves periods over the width.
      if (c.num_waves < 1) return fail("num_waves", "expected a positive integer");
      const real div = ly / (static_cast<real>(c.num_waves) * kTwoPi);
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i)
          at(i, j) = c.amplitude_m * std::cos(static_cast<real>(j) * hs / div) + c.amplitude_m * std::sin(static_cast<real>(i) * hs / div);
    } else {
      return fail("procedural", "unknown generator \"" + p + "\"; allowed: " + terrain_procedural_names());
    }
  }
  for (real v : h)
    if (!std::isfinite(v)) return fail(c.heights_m.empty() ? "image_file" : "heights_m", "non-finite height");
  heights_ = std::move(h);
  hf_.heights = heights_.data();
  hf_.nx = static_cast<std::uint32_t>(nx);
  hf_.ny = static_cast<std::uint32_t>(ny);
  hf_.dx = hf_.dy = hs;
  if (sensors::height_field_prepare(hf_) != Status::ok) return fail("heights_m", "invalid height field");
  scene_position_w_ = Vec3(c.origin_m[0] - static_cast<real>(nx - 1) * hs / 2, c.origin_m[1] - static_cast<real>(ny - 1) * hs / 2, c.origin_m[2]);
  for (Vec3& o : tile_origins_) o += scene_position_w_;
  return true;
}

bool SceneMesh::build(const TriangleMesh& m, const Vec3& offset) {
  const std::uint32_t nt = static_cast<std::uint32_t>(m.triangles.size());
  vertices.resize(3 * m.vertices.size());
  for (std::size_t v = 0; v < m.vertices.size(); ++v)
    for (int k = 0; k < 3; ++k) vertices[3 * v + k] = m.vertices[v][k] + offset[k];
  indices.resize(3 * static_cast<std::size_t>(nt));
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) indices[3 * t + k] = static_cast<std::uint32_t>(m.triangles[t][k]);
  nodes.assign(sensors::bvh_node_capacity(nt), sensors::BvhNode());
  prim_index.assign(nt, 0);
  triangle_cache.assign(static_cast<std::size_t>(sensors::kTriangleCacheStride) * nt, 0);
  std::vector<sensors::Aabb> scratch(nt);
  mesh = sensors::TriangleMesh();
  mesh.vertices = vertices.data();
  mesh.vertex_count = static_cast<std::uint32_t>(m.vertices.size());
  mesh.indices = indices.data();
  mesh.triangle_count = nt;
  sensors::MeshStorage st;
  st.nodes = nodes.data();
  st.node_capacity = static_cast<std::uint32_t>(nodes.size());
  st.prim_index = prim_index.data();
  st.triangle_cache = triangle_cache.data();
  st.scratch_boxes = scratch.data();
  st.triangle_capacity = nt;
  return sensors::mesh_build(mesh, st) == Status::ok;
}

bool Terrain::build_trimesh(const TerrainConfig& c, std::string& error) {
  if (c.mesh_file.empty()) return error = where(c, "mesh_file") + "missing (type trimesh needs an .obj or .stl file)", false;
  if (!c.origin_m.allFinite()) return error = where(c, "origin_m") + "expected finite numbers", false;
  TriangleMesh m;
  std::string merr;
  if (!load_mesh(c.mesh_file, m, merr)) return error = where(c, "mesh_file") + merr, false;
  if (!trimesh_.build(m, c.origin_m)) return error = where(c, "mesh_file") + c.mesh_file + ": mesh BVH build failed", false;
  return true;
}

real Terrain::hf_local_height(real x, real y) const {
  // Clamp to the grid (legged_gym clips its sample indices the same way).
  const real xmax = static_cast<real>(hf_.nx - 1) * hf_.dx, ymax = static_cast<real>(hf_.ny - 1) * hf_.dy;
  x = std::min(xmax, std::max(0_r, x));
  y = std::min(ymax, std::max(0_r, y));
  const real gx = x / hf_.dx, gy = y / hf_.dy;  // grid coordinates
  const int i = std::min(static_cast<int>(hf_.nx) - 2, static_cast<int>(gx));
  const int j = std::min(static_cast<int>(hf_.ny) - 2, static_cast<int>(gy));
  const real u = gx - static_cast<real>(i), v = gy - static_cast<real>(j);
  const std::size_t r0 = static_cast<std::size_t>(j) * hf_.nx, r1 = r0 + hf_.nx;
  const real h00 = heights_[r0 + i], h10 = heights_[r0 + i + 1], h01 = heights_[r1 + i], h11 = heights_[r1 + i + 1];
  // Triangle 0: (i,j), (i+1,j), (i+1,j+1) where u >= v; triangle 1: (i,j), (i+1,j+1), (i,j+1).
  return u >= v ? h00 + u * (h10 - h00) + v * (h11 - h10) : h00 + v * (h01 - h00) + u * (h11 - h01);
}

real Terrain::height_at(real x_w, real y_w) const {
  if (type_ == TerrainType::heightfield)
    return scene_position_w_[2] + hf_local_height(x_w - scene_position_w_[0], y_w - scene_position_w_[1]);
  if (type_ == TerrainType::trimesh) {
    const sensors::TriangleMesh& mesh = trimesh_.mesh;
    const real o[3] = {x_w, y_w, mesh.bounds.hi[2] + 1}, d[3] = {0, 0, -1};
    const sensors::Ray ray = sensors::make_ray(o, d);
    real tmax = mesh.bounds.hi[2] - mesh.bounds.lo[2] + 2;
    std::uint32_t tri = 0;
    return sensors::mesh_intersect(mesh, ray, 0, tmax, tri) ? o[2] - tmax : mesh.bounds.lo[2];
  }
  return 0;
}

int Terrain::collide(const Shape& s, real bound_radius_m, Contact* out) const {
  int count = 0;
  Vec3 mn, mx;
  shape_aabb(s, mn, mx);
  const real back = 2 * bound_radius_m;
  Contact k;
  if (type_ == TerrainType::heightfield) {
    const Vec3 lo = mn - scene_position_w_, hi = mx - scene_position_w_;
    const real dx = hf_.dx, dy = hf_.dy;
    const int ncx = static_cast<int>(hf_.nx) - 1, ncy = static_cast<int>(hf_.ny) - 1;
    if (!(hi[0] >= 0 && hi[1] >= 0 && lo[0] <= static_cast<real>(ncx) * dx && lo[1] <= static_cast<real>(ncy) * dy)) return 0;  // NaN too
    // Clamped to the grid before the float -> int conversion (no overflow for far-away shapes).
    const real ex = static_cast<real>(ncx - 1), ey = static_cast<real>(ncy - 1);
    const int i0 = static_cast<int>(std::floor(std::max(0_r, lo[0] / dx))), i1 = static_cast<int>(std::min(ex, std::floor(hi[0] / dx)));
    const int j0 = static_cast<int>(std::floor(std::max(0_r, lo[1] / dy))), j1 = static_cast<int>(std::min(ey, std::floor(hi[1] / dy)));
    const Vec3& o = scene_position_w_;
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        const std::size_t r0 = static_cast<std::size_t>(j) * hf_.nx, r1 = r0 + hf_.nx;
        const real h00 = heights_[r0 + i], h10 = heights_[r0 + i + 1], h01 = heights_[r1 + i], h11 = heights_[r1 + i + 1];
        if (std::max(std::max(h00, h10), std::max(h01, h11)) < lo[2]) continue;  // the shape is above this cell
        const real x0 = static_cast<real>(i) * dx, y0 = static_cast<real>(j) * dy;
        const Vec3 a = o + Vec3(x0, y0, h00), b = o + Vec3(x0 + dx, y0, h10), c = o + Vec3(x0 + dx, y0 + dy, h11),
                   d = o + Vec3(x0, y0 + dy, h01);
        if (triangle_contact(s, a, b, c, back, k)) merge_contact(k, out, count);
        if (triangle_contact(s, a, c, d, back, k)) merge_contact(k, out, count);
      }
    }
    return count;
  }
  const sensors::TriangleMesh& mesh = trimesh_.mesh;
  if (type_ != TerrainType::trimesh || mesh.bvh.node_count == 0) return 0;
  // Overlap walk of the mesh BVH (left child first: a fixed visit order).
  const sensors::BvhNode* nodes = mesh.bvh.nodes;
  auto overlaps = [&](const sensors::BvhNode& nd) {
    return !(nd.hi[0] < mn[0] || nd.lo[0] > mx[0] || nd.hi[1] < mn[1] || nd.lo[1] > mx[1] || nd.hi[2] < mn[2] - back ||
             nd.lo[2] > mx[2] + back);
  };
  std::uint32_t stack[sensors::kBvhMaxDepth];
  int sp = 0;
  if (overlaps(nodes[0])) stack[sp++] = 0;
  while (sp > 0) {
    const sensors::BvhNode& nd = nodes[stack[--sp]];
    if (nd.count == 0) {
      if (overlaps(nodes[nd.first + 1])) stack[sp++] = nd.first + 1;
      if (overlaps(nodes[nd.first])) stack[sp++] = nd.first;
      continue;
    }
    for (std::uint32_t q = 0; q < nd.count; ++q) {
      const std::uint32_t t = mesh.bvh.prim_index[nd.first + q];
      const real* v0 = &mesh.vertices[3 * mesh.indices[3 * t]];
      const real* v1 = &mesh.vertices[3 * mesh.indices[3 * t + 1]];
      const real* v2 = &mesh.vertices[3 * mesh.indices[3 * t + 2]];
      if (triangle_contact(s, Vec3(v0[0], v0[1], v0[2]), Vec3(v1[0], v1[1], v1[2]), Vec3(v2[0], v2[1], v2[2]), back, k))
        merge_contact(k, out, count);
    }
  }
  return count;
}

sensors::Shape Terrain::scene_shape() const {
  if (type_ == TerrainType::heightfield) return sensors::Shape::heights(&hf_);
  if (type_ == TerrainType::trimesh) return sensors::Shape::triangle_mesh(&trimesh_.mesh);
  return sensors::Shape::plane();
}

}  // namespace kestrel::sim
