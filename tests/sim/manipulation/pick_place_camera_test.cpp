// The pick-and-place cameras (sim/pick_place_camera.hpp): a pixel on the cube's top face has the
// depth the geometry gives and the cube's red with the Lambert intensity ambient + diffuse n . l;
// an oblique pixel's depth on the table matches the hand-computed ray-plane hit; the front
// camera's centre pixel sees what its optical axis hits; pixels past the table's edge read the
// no-hit values; the wrist camera sees the cube between the pads after a scripted grasp; same
// state -> identical bytes; no heap in a render; bad arguments refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "heap_counter.hpp"
#include "kestrel/sim/pick_place.hpp"
#include "kestrel/sim/pick_place_camera.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

constexpr std::uint8_t kTable = static_cast<std::uint8_t>(PickPlaceEntity::table);
constexpr std::uint8_t kRobot = static_cast<std::uint8_t>(PickPlaceEntity::robot);
constexpr std::uint8_t kCube = static_cast<std::uint8_t>(PickPlaceEntity::cube);

PickPlaceConfig fixed_scene() {
  PickPlaceConfig c;
  c.randomize_xy_m = 0;  // cube at (0.20, 0), box at (0.20, 0.15)
  return c;
}

void init_or_fail(PickPlaceWorld& w, const PickPlaceConfig& c, std::uint64_t seed = 1) {
  std::string err;
  ASSERT_TRUE(w.init(c, seed, 0, err)) << err;
}

struct Frame {
  int W, H;
  std::vector<std::uint8_t> rgb, seg;
  std::vector<float> depth;
  Frame(int w, int h) : W(w), H(h), rgb(static_cast<std::size_t>(w) * h * 3), seg(static_cast<std::size_t>(w) * h), depth(static_cast<std::size_t>(w) * h) {}
  std::size_t at(int col, int row) const { return static_cast<std::size_t>(row) * W + col; }
  float d(int col, int row) const { return depth[at(col, row)]; }
  std::uint8_t s(int col, int row) const { return seg[at(col, row)]; }
  const std::uint8_t* px(int col, int row) const { return &rgb[3 * at(col, row)]; }
};

Frame render_or_fail(const PickPlaceWorld& w, const CameraSpec& cam) {
  Frame f(cam.width, cam.height);
  EXPECT_EQ(render_camera(w, cam, f.rgb.data(), f.depth.data(), f.seg.data()), Status::ok);
  return f;
}

// The world ray of pixel (col, row) as the header defines it: (1, (W/2 - col - 0.5)/f, (H/2 - row - 0.5)/f).
Vec3 pixel_ray_w(const CameraSpec& cam, const Mat3& R_wc, int col, int row) {
  const double f = cam.width / 2.0 / std::tan(cam.hfov_rad / 2.0);
  const Vec3 d_c(1, static_cast<real>((cam.width / 2.0 - col - 0.5) / f), static_cast<real>((cam.height / 2.0 - row - 0.5) / f));
  return R_wc * d_c;
}

std::uint8_t expected_channel(real albedo, real intensity) {
  const double v = static_cast<double>(albedo) * 255.0 * static_cast<double>(intensity) + 0.5;
  return v >= 255 ? 255 : static_cast<std::uint8_t>(v);
}

}  // namespace

TEST(PickPlaceCamera, CubeTopFaceDepthAndLambertRed) {
  PickPlaceWorld w;
  init_or_fail(w, fixed_scene());
  const real top = 2 * w.config().cube_half_m;  // 0.025 m
  // Straight down from 6 cm above the table, over the cube's centre (below the gripper, which
  // hovers 9 cm up at home): the top face is normal to the optical axis, so every pixel on it
  // has depth 0.06 - 0.025 = 0.035 m.
  const CameraSpec cam = look_at_camera(Vec3(0.20_r, 0, 0.06_r), Vec3(0.20_r, 0, 0), 0.8_r, 160, 120);
  const Frame f = render_or_fail(w, cam);
  const int col = 80, row = 60;
  ASSERT_EQ(f.s(col, row), kCube);
  EXPECT_NEAR(f.d(col, row), 0.06 - top, 1e-6);
  // Lambert: the face's normal is +z, so n . l = l_z; I = ambient + diffuse max(0, l_z).
  const CameraLook look;
  const real I = look.ambient + look.diffuse * std::max<real>(0, look.light_dir_w[2]);
  EXPECT_NEAR(I, 0.35 + 0.65 * 0.91823214, 1e-6);  // 0.94685
  const std::uint8_t* p = f.px(col, row);
  EXPECT_EQ(p[0], expected_channel(look.cube_rgb[0], I));
  EXPECT_EQ(p[1], expected_channel(look.cube_rgb[1], I));
  EXPECT_EQ(p[2], expected_channel(look.cube_rgb[2], I));
  EXPECT_EQ(p[0], 205);  // 0.85 x 255 x 0.94685 = 205.2
  EXPECT_EQ(p[1], 24);   // 0.10 x 255 x 0.94685 = 24.1
  EXPECT_GT(p[0], 4 * p[1]);  // red hue

  // Obliquely: a pixel whose ray meets the cube's top face; its depth is t with
  // eye_z + t d_z = 0.025 for the unnormalised ray d (x component 1 in the camera frame).
  const CameraSpec ob = look_at_camera(Vec3(0.35_r, 0.04_r, 0.09_r), Vec3(0.20_r, 0, top), 1.0_r, 200, 150);
  Vec3 eye;
  Mat3 R_wc;
  camera_pose_w(w, ob, eye, R_wc);
  const Frame g = render_or_fail(w, ob);
  int checked = 0;
  for (int r = 60; r < 90; r += 7)
    for (int c = 85; c < 115; c += 7) {
      const Vec3 d = pixel_ray_w(ob, R_wc, c, r);
      const real t = (top - eye[2]) / d[2];
      const Vec3 hit = eye + t * d;
      if (std::fabs(hit[0] - 0.20_r) > 0.012_r || std::fabs(hit[1]) > 0.012_r) continue;  // off the top face
      EXPECT_EQ(g.s(c, r), kCube) << c << "," << r;
      EXPECT_NEAR(g.d(c, r), t, 2e-5) << c << "," << r;
      EXPECT_EQ(g.px(c, r)[0], 205);
      ++checked;
    }
  EXPECT_GE(checked, 4);
}

TEST(PickPlaceCamera, FrontCameraCentrePixelSeesItsOpticalAxisHit) {
  PickPlaceWorld w;
  init_or_fail(w, fixed_scene());
  const CameraSpec cam = front_camera();
  ASSERT_EQ(cam.width, 640);
  ASSERT_EQ(cam.height, 480);
  const Frame f = render_or_fail(w, cam);
  // The optical axis (the camera's x) from (0.55, 0, 0.35) towards (0.15, 0.05, 0.08) meets the
  // table at eye + t_axis x with t_axis = -eye_z / x_z (unit axis: t is also the depth), at
  // (0.03, 0.065, 0), clear of the arm's base (|y| < 0.04) and of the cube.
  Vec3 eye;
  Mat3 R_wc;
  camera_pose_w(w, cam, eye, R_wc);
  const Vec3 axis = R_wc.col(0);
  const real t_axis = -eye[2] / axis[2];
  const Vec3 hit_axis = eye + t_axis * axis;
  EXPECT_NEAR(hit_axis[0], 0.15 + (0.15 - 0.55) * 0.08 / 0.27, 1e-4);
  EXPECT_NEAR(hit_axis[1], 0.05 + 0.05 * 0.08 / 0.27, 1e-4);
  EXPECT_NEAR(t_axis, std::sqrt(0.4 * 0.4 + 0.05 * 0.05 + 0.27 * 0.27) * 0.35 / 0.27, 1e-5);  // 0.6289 m
  const int col = 320, row = 240;
  EXPECT_EQ(f.s(col, row), kTable);
  EXPECT_NEAR(f.d(col, row), t_axis, 2e-3);  // the pixel's centre is half a pixel off the axis
  // Exactly: the centre pixel's own ray meets the plane z = 0.
  const Vec3 d = pixel_ray_w(cam, R_wc, col, row);
  EXPECT_NEAR(f.d(col, row), -eye[2] / d[2], 2e-5);
  // Wood brown, lit from above: I = ambient + diffuse l_z, as on the cube's top.
  const CameraLook look;
  const real I = look.ambient + look.diffuse * look.light_dir_w[2];
  EXPECT_EQ(f.px(col, row)[0], expected_channel(look.table_rgb[0], I));
  EXPECT_EQ(f.px(col, row)[1], expected_channel(look.table_rgb[1], I));
  EXPECT_EQ(f.px(col, row)[2], expected_channel(look.table_rgb[2], I));
  // It sees the arm, the cube and the box.
  int counts[256] = {};
  for (std::uint8_t s : f.seg) ++counts[s];
  EXPECT_GT(counts[kRobot], 2000);
  EXPECT_GT(counts[kCube], 300);
  EXPECT_GT(counts[static_cast<int>(PickPlaceEntity::box)], 2000);
}

TEST(PickPlaceCamera, PastTheTableEdgeAndTheSkyReadNoHit) {
  PickPlaceWorld w;
  init_or_fail(w, fixed_scene());
  // Straight down from above x = 1.0 (the table ends at x = 0.9): the image's left edge (world
  // -x, the camera's +y) still sees the table top at depth 0.3, its centre sees nothing.
  const CameraSpec cam = look_at_camera(Vec3(1.0_r, 0, 0.3_r), Vec3(1.0_r, 0, 0), 1.2217305_r, 160, 120);
  const Frame f = render_or_fail(w, cam);
  EXPECT_EQ(f.s(2, 60), kTable);
  EXPECT_NEAR(f.d(2, 60), 0.3, 1e-5);
  EXPECT_TRUE(std::isinf(f.d(80, 60)) && f.d(80, 60) > 0);
  EXPECT_EQ(f.s(80, 60), kCameraNoHitSegment);
  const CameraLook look;
  EXPECT_EQ(f.px(80, 60)[0], look.sky_rgb[0]);
  EXPECT_EQ(f.px(80, 60)[1], look.sky_rgb[1]);
  EXPECT_EQ(f.px(80, 60)[2], look.sky_rgb[2]);
  // The front camera's top corners look over the table's far edge at the sky.
  const Frame g = render_or_fail(w, front_camera(160, 120));
  EXPECT_TRUE(std::isinf(g.d(0, 0)));
  EXPECT_EQ(g.s(159, 0), kCameraNoHitSegment);
}

TEST(PickPlaceCamera, WristCameraSeesTheCubeBetweenThePadsAfterAGrasp) {
  PickPlaceWorld w;
  init_or_fail(w, fixed_scene());
  ScriptedPickPlace s(w);
  real a[PickPlaceWorld::kJoints];
  int steps = 0;
  while (s.phase() <= 3 && steps < 400) {  // approach, descend, close, lift
    s.act(a);
    ASSERT_EQ(w.step(a), Status::ok);
    ++steps;
  }
  ASSERT_GT(w.state().cube_pos_w[2], w.config().cube_half_m + 0.03_r);  // lifted
  const CameraSpec cam = wrist_camera(w);
  const Frame f = render_or_fail(w, cam);
  // The cube fills the middle of the image, a few centimetres away (the camera 5.5 cm above
  // the tool centre point, 3 cm to its side).
  int cube = 0;
  for (int r = 200; r < 280; ++r)
    for (int c = 280; c < 360; ++c) cube += f.s(c, r) == kCube;
  EXPECT_GT(cube, 80 * 80 / 2);
  EXPECT_EQ(f.s(320, 240), kCube);
  EXPECT_GT(f.d(320, 240), 0.02);
  EXPECT_LT(f.d(320, 240), 0.07);
  // The camera's ray to the cube's centre: the first thing it meets is the cube.
  Vec3 eye;
  Mat3 R_wc;
  camera_pose_w(w, cam, eye, R_wc);
  const Vec3 to_cube_c = R_wc.transpose() * (w.state().cube_pos_w - eye);
  ASSERT_GT(to_cube_c[0], 0);
  const double fpx = cam.width / 2.0 / std::tan(cam.hfov_rad / 2.0);
  const int col = static_cast<int>(cam.width / 2.0 - fpx * to_cube_c[1] / to_cube_c[0]);
  const int row = static_cast<int>(cam.height / 2.0 - fpx * to_cube_c[2] / to_cube_c[0]);
  ASSERT_TRUE(col >= 0 && col < cam.width && row >= 0 && row < cam.height);
  EXPECT_EQ(f.s(col, row), kCube);
  EXPECT_LT(f.d(col, row), to_cube_c[0]);  // its near face, before the centre
  // Both pads are in view beside it (robot pixels left and right of the cube on its row).
  int robot_left = 0, robot_right = 0;
  for (int c = 0; c < col; ++c) robot_left += f.s(c, row) == kRobot;
  for (int c = col; c < cam.width; ++c) robot_right += f.s(c, row) == kRobot;
  EXPECT_GT(robot_left, 5);
  EXPECT_GT(robot_right, 5);
}

TEST(PickPlaceCamera, SameStateSameBytesAndNoHeap) {
  PickPlaceWorld w1, w2;
  init_or_fail(w1, PickPlaceConfig(), 7);
  init_or_fail(w2, PickPlaceConfig(), 7);
  real a[PickPlaceWorld::kJoints];
  for (int j = 0; j < PickPlaceWorld::kJoints; ++j) a[j] = w1.home()[j];
  a[0] += 0.3_r;
  a[3] -= 0.2_r;
  for (int k = 0; k < 10; ++k) {
    ASSERT_EQ(w1.step(a), Status::ok);
    ASSERT_EQ(w2.step(a), Status::ok);
  }
  for (int which = 0; which < 2; ++which) {
    const CameraSpec cam = which == 0 ? front_camera() : wrist_camera(w1);
    Frame f1(cam.width, cam.height), f2(cam.width, cam.height), f3(cam.width, cam.height);
    {
      kestrel::test::HeapCounter heap;
      ASSERT_EQ(render_camera(w1, cam, f1.rgb.data(), f1.depth.data(), f1.seg.data()), Status::ok);
      ASSERT_EQ(render_camera(w1, cam, f2.rgb.data(), f2.depth.data(), f2.seg.data()), Status::ok);
      ASSERT_EQ(render_camera(w2, cam, f3.rgb.data(), f3.depth.data(), f3.seg.data()), Status::ok);
      ASSERT_EQ(render_camera(w1, cam, nullptr, f3.depth.data(), nullptr), Status::ok);  // outputs optional
      EXPECT_EQ(heap.allocations(), 0u);
    }
    EXPECT_EQ(std::memcmp(f1.rgb.data(), f2.rgb.data(), f1.rgb.size()), 0);
    EXPECT_EQ(std::memcmp(f1.depth.data(), f2.depth.data(), f1.depth.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(f1.seg.data(), f2.seg.data(), f1.seg.size()), 0);
    EXPECT_EQ(std::memcmp(f1.rgb.data(), f3.rgb.data(), f1.rgb.size()), 0);
    EXPECT_EQ(std::memcmp(f1.depth.data(), f3.depth.data(), f1.depth.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(f1.seg.data(), f3.seg.data(), f1.seg.size()), 0);
  }
}

TEST(PickPlaceCamera, BadArgumentsAreRefused) {
  PickPlaceWorld w;
  init_or_fail(w, fixed_scene());
  std::vector<float> depth(16, 1.0f);
  CameraSpec cam = front_camera(4, 4);
  cam.width = 0;
  EXPECT_EQ(render_camera(w, cam, nullptr, depth.data()), Status::invalid_argument);
  cam = front_camera(4, 4);
  cam.hfov_rad = 0;
  EXPECT_EQ(render_camera(w, cam, nullptr, depth.data()), Status::invalid_argument);
  cam = front_camera(4, 4);
  cam.pos_m[0] = NAN;
  EXPECT_EQ(render_camera(w, cam, nullptr, depth.data()), Status::invalid_argument);
  cam = front_camera(kMaxCameraWidth + 1, 4);
  EXPECT_EQ(render_camera(w, cam, nullptr, depth.data()), Status::invalid_argument);
  for (float d : depth) EXPECT_EQ(d, 1.0f);  // nothing written
}
