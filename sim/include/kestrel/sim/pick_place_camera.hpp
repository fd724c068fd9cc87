// Cameras of the SO-101 pick-and-place scene (issue 14's "Cameras", LeIsaac's front and wrist
// cameras): an RGB image and a depth image of PickPlaceWorld at its current state, ray cast
// analytically against the scene's collision primitives (PickPlaceWorld::scene_shapes(): the
// arm's boxes/capsules/spheres, the cube, the box's five parts), the robot file's world-fixed
// geoms (the arm's base) and the table (the USD scene's table box, its top the plane z = 0).
//
// Camera model: pinhole, square pixels, horizontal field of view hfov_rad, principal point at the
// image centre (W/2, H/2); f_px = (W/2) / tan(hfov/2). Pixel (col, row) is the ray through its
// centre (col + 0.5, row + 0.5). Camera frame = the sensors' _s frame: x forward along the
// optical axis, y left, z up (row 0 is the top of the image, column 0 its left edge), so the ray
// of pixel (col, row) is (1, (W/2 - col - 0.5) / f_px, (H/2 - row - 0.5) / f_px) in the camera
// frame.
//
// Outputs (caller storage, row-major, row 0 at the top):
//  - rgb: 3 bytes per pixel, the entity's (or robot part's) albedo times the Lambert intensity
//    I = ambient + diffuse * max(0, n . l) (n the hit's outward unit normal, l the unit direction
//    towards the light, both world frame), each channel min(255, floor(albedo * 255 * I + 0.5));
//    the sky colour where the ray hits nothing.
//  - depth_m: float32, depth along the optical axis (the distance to the image plane, Isaac's
//    distance_to_image_plane), metres; +infinity where the ray hits nothing within
//    [near_m, far_m].
//  - segmentation (optional): the PickPlaceEntity (table 0, robot 1, cube 2, box 3), 255 for no hit.
//
// Speed: the rays of one camera share its origin, so each primitive's bounding sphere is
// projected once per frame into a conservative pixel rectangle (exact for a sphere's projection
// on each image axis, plus a pixel of margin); each row then tests only the primitives whose
// rectangle covers it, over their column spans, with the origin moved into each primitive's frame
// once per frame and the ray directions stepped linearly along the row (unnormalised rays, so the
// hit parameter is the depth itself). Intersections: sensors/geometry.hpp's (slab box, capsule,
// sphere).
//
// Determinism: same state -> same bytes (one thread, a fixed order; equal depths go to the first
// primitive in the order table, base geoms, scene_shapes()). No heap inside render_camera: the
// per-frame tables and one row of hit records live on the stack (width <= kMaxCameraWidth).
#pragma once

#include <cstdint>
#include <string>

#include "kestrel/kernel/status.hpp"
#include "kestrel/sim/pick_place.hpp"

namespace kestrel::sim {

constexpr int kMaxCameraWidth = 2048;
constexpr int kMaxCameraHeight = 2048;
/// Primitives one frame can hold (the SO-101 scene has 21 plus the base's).
constexpr int kMaxCameraShapes = 64;
constexpr std::uint8_t kCameraNoHitSegment = 255;

/// A pinhole camera fixed on a body of the arm (attach_body >= 0, its pose follows the body) or in
/// the world (attach_body = -1).
struct CameraSpec {
  Vec3 pos_m = Vec3::Zero();     // the camera's origin in attach_body's frame (the world's for -1)
  Mat3 R = Mat3::Identity();     // camera -> attach_body's frame (columns: the camera's x fwd, y left, z up)
  int attach_body = -1;
  int width = 640, height = 480;
  real hfov_rad = 1.2217305_r;   // 70 deg
  real near_m = 0.01_r;          // depth range of a hit
  real far_m = 10;
};

/// Colours and light. Albedos are linear 0..1 per channel.
struct CameraLook {
  Vec3 light_dir_w = Vec3(0.32444284_r, 0.22710999_r, 0.91823214_r);  // towards the light, unit: normalise(1, 0.7, 2.83)
  real ambient = 0.35_r;
  real diffuse = 0.65_r;
  Vec3 table_rgb = Vec3(0.55_r, 0.40_r, 0.25_r);   // the USD scene's displayColor (wood)
  Vec3 cube_rgb = Vec3(0.85_r, 0.10_r, 0.10_r);    // red
  Vec3 box_rgb = Vec3(0.20_r, 0.40_r, 0.80_r);     // blue
  Vec3 robot_rgb = Vec3(0.95_r, 0.55_r, 0.15_r);   // the printed links: orange
  Vec3 robot_dark_rgb = Vec3(0.30_r, 0.30_r, 0.33_r);  // motors, pads, the wrist's roll follower: grey
  std::uint8_t sky_rgb[3] = {200, 215, 230};
  // The table as drawn (the USD scene's: 1.2 x 0.8 m, 0.75 m tall, top at z = 0); the physics
  // treats it as the plane z = 0, so a ray past its edge sees the sky.
  Vec3 table_center_w = Vec3(0.3_r, 0, -0.375_r);
  Vec3 table_half_m = Vec3(0.6_r, 0.4_r, 0.375_r);
};

/// A camera at eye_w looking at target_w, its image's up towards the world's +z (attach_body -1).
CameraSpec look_at_camera(const Vec3& eye_w, const Vec3& target_w, real hfov_rad, int width = 640, int height = 480);
/// LeIsaac-like front camera: fixed in the world in front of the robot, at (0.55, 0, 0.35) looking
/// back at (0.15, 0.05, 0.08) (its optical axis meets the table at (0.03, 0.065, 0), beside the
/// arm's base): sees the whole arm, the cube and the box. 70 deg horizontal field of view.
CameraSpec front_camera(int width = 640, int height = 480);
/// LeIsaac-like wrist camera: fixed on the tool-centre-point body (world.tcp_body(), rigid on the
/// gripper; fingers along its -z, the pads' normals along its x), on the side of the gripper's
/// housing (3 cm to the tcp body's -y, 5.5 cm above the tool centre point) looking down along the
/// fingers at a point 1.5 cm beyond the tool centre point, so the gap between the pads sits
/// near the image centre; image up towards the wrist. 90 deg horizontal field of view.
CameraSpec wrist_camera(const PickPlaceWorld& world, int width = 640, int height = 480);
/// The camera's pose in the world at the world's current state: origin and camera -> world rotation.
void camera_pose_w(const PickPlaceWorld& world, const CameraSpec& cam, Vec3& pos_w, Mat3& R_wc);

/// Renders one frame. rgb (h*w*3), depth_m (h*w) and segmentation (h*w) may each be null (not
/// written). invalid_argument (nothing written) for a size outside 1..kMaxCameraWidth x
/// 1..kMaxCameraHeight, a field of view outside (0, pi), a bad depth range or a non-finite pose;
/// capacity_exceeded if the scene has more than kMaxCameraShapes primitives.
[[nodiscard]] Status render_camera(const PickPlaceWorld& world, const CameraSpec& cam, std::uint8_t* rgb, float* depth_m,
                                   std::uint8_t* segmentation = nullptr, const CameraLook& look = CameraLook());

/// Writes rgb as an 8-bit RGB PNG at rgb_path and depth_m as a 16-bit greyscale PNG in
/// millimetres at depth_path (rounded, clamped to 65535; no hit -> 0). Either path may be empty.
/// Set-up / output code: allocates. False with a message naming the file.
[[nodiscard]] bool write_camera_pngs(const std::string& rgb_path, const std::string& depth_path, int width, int height,
                                     const std::uint8_t* rgb, const float* depth_m, std::string& error);

}  // namespace kestrel::sim
