// Ray-pattern sensors: lidar (and the multizone ToF, which is a small lidar grid), pinhole depth
// camera, their Aerial Gym-compatible post-processing, noise and mounting.
//
// Ray tables follow ../shared/golden/sensor_rays.json exactly:
//  - lidar row i, column j: azimuth = hmax - (hmax - hmin) j / (W - 1), elevation =
//    vmax - (vmax - vmin) i / (H - 1), dir = (cos az cos el, sin az cos el, sin el) in float64,
//    stored in `real` and normalised again (row 0 = top, column 0 = most positive azimuth).
//  - camera: f = (W/2) / tan(hfov/2), integer pixel coordinates, principal point (W/2, H/2),
//    optical dir ((x - u0)/f, (y - v0)/f, 1) normalised, sensor = (z_opt, -x_opt, -y_opt);
//    depth = range * (dir . principal dir of pixel (int(W/2), int(H/2))) (golden quirk 11).
// Frames: _s sensor (x forward, y left, z up), _b body, _w world.
//
// Pixel pipeline (golden depth_range_convention): cast up to max_range (camera depth: up to
// max_range / depth_scale, so the far cut is a plane) -> raw value (range or depth; no hit ->
// kNoHitValue) -> optional noise -> > max_range: far_out_of_range_value, < min_range:
// near_out_of_range_value -> optional division by max_range.
#pragma once

#include <cstdint>

#include "kestrel/kernel/rng.hpp"
#include "kestrel/kernel/status.hpp"
#include "kestrel/kernel/types.hpp"
#include "kestrel/sensors/scene.hpp"

namespace kestrel::sensors {

constexpr real kNoHitValue = 1000;          // m, Aerial Gym's no-hit value before post-processing
constexpr std::int32_t kNoHitSegment = -1;  // segmentation value of a pixel without a hit

/// Range post-processing shared by all ray sensors.
struct RangeOutputParams {
  real min_range = 0.2_r;  // m
  real max_range = 10;     // m
  bool normalize_range = false;
  // Aerial Gym: with normalisation far = +max_range, near = -max_range (1 and -1 after the
  // division); without, both are -1. set_default_out_of_range_values() applies that rule.
  real far_out_of_range_value = -1;
  real near_out_of_range_value = -1;
  void set_default_out_of_range_values() {
    far_out_of_range_value = normalize_range ? max_range : -1_r;
    near_out_of_range_value = normalize_range ? -max_range : -1_r;
  }
};

struct LidarParams {
  std::uint32_t height = 64;  // scan lines
  std::uint32_t width = 512;  // points per line
  real horizontal_fov_deg_min = -180, horizontal_fov_deg_max = 180;
  real vertical_fov_deg_min = 0, vertical_fov_deg_max = 90;
  RangeOutputParams range{0.5_r, 20, false, -1, -1};
};

struct CameraParams {
  std::uint32_t height = 135;  // rows
  std::uint32_t width = 240;   // columns
  real horizontal_fov_deg = 87;
  bool calculate_depth = true;  // depth along the optical axis (else range along the ray)
  RangeOutputParams range{0.2_r, 10, false, -1, -1};
};

// Presets. Sources: the numbers where given; otherwise manufacturer datasheets as noted.
/// Aerial Gym OSDome 64x512, h -180..180 deg, v 0..90 deg, 0.5-20 m.
LidarParams lidar_preset_osdome_64();
/// Ouster OS0-128: 128 x 512, vertical FOV 90 deg (+-45), 0.3-35 m (datasheet rev7: 35 m at
/// 10 % reflectivity; 0.3 m minimum range). Columns: 512 (also sold as 1024/2048).
LidarParams lidar_preset_os0_128();
/// Ouster OS0-64: as OS0-128 with 64 beams.
LidarParams lidar_preset_os0_64();
/// Ouster OS1-64: 64 x 512, +-22.5 deg, 0.3-120 m (datasheet: 120 m at 80 % reflectivity).
LidarParams lidar_preset_os1_64();
/// Ouster OS2-64: 64 x 512, +-11.25 deg, 0.8-240 m (datasheet: 240 m at 80 %, 0.8 m minimum).
LidarParams lidar_preset_os2_64();
/// RoboSense RS-Airy as sampled in the issue: 48 x 120, h 360 deg, v 0..90 deg, 0.1-30 m
/// (assumption: hemispherical dome like the OSDome; datasheet range 0.1-30 m at 10 %).
LidarParams lidar_preset_rs_airy();
/// pmd flexx2 ToF camera treated as a ray grid: 172 x 224, 56 x 44 deg FOV, 0.1-4 m (datasheet).
LidarParams lidar_preset_pmd_flexx2();
/// ST VL53L5CX multizone ToF: 8 x 8 zones, 45 x 45 deg square FOV (63 deg diagonal), 0.02-4 m.
LidarParams lidar_preset_vl53l5cx();
/// Aerial Gym base depth camera: 135 x 240, hfov 87 deg, 0.2-10 m.
CameraParams camera_preset_base();
/// Intel RealSense D455: 270 x 480 (half of 720p), depth hfov 87 deg (datasheet 87 x 58), 0.4-10 m
/// (datasheet ideal range 0.6-6 m, min-Z ~0.52 m at 1280 x 720; assumption: Aerial Gym-like 10 m cap).
CameraParams camera_preset_d455();
/// Luxonis OAK-D: 400 x 640 stereo depth (OV9282 mono pair), hfov 71.9 deg, 0.35-20 m (datasheet
/// ideal range 0.7-12 m; min 0.35 m with extended disparity).
CameraParams camera_preset_oakd();

/// Sensor-frame ray table in caller storage: dirs_s (3 reals per ray, row-major image order) and
/// depth_scale (1 per ray: dir . principal dir for a depth camera, 1 otherwise).
struct RayTable {
  real* dirs_s = nullptr;
  real* depth_scale = nullptr;
  std::uint32_t capacity = 0;  // rays
  std::uint32_t height = 0, width = 0;
};

/// One ray of the pattern (sensor frame, unit); row i, column j. depth_scale as in RayTable.
void lidar_ray(const LidarParams& p, std::uint32_t row, std::uint32_t col, real dir_s[3]);
void camera_ray(const CameraParams& p, std::uint32_t row, std::uint32_t col, real dir_s[3], real& depth_scale);

/// Fills the table (capacity must hold height x width rays, else capacity_exceeded).
[[nodiscard]] Status lidar_rays(const LidarParams& p, RayTable& table);
[[nodiscard]] Status camera_rays(const CameraParams& p, RayTable& table);

/// Pose of the sensor frame in the world (q_ws rotates sensor vectors into the world).
struct SensorPose {
  Vec3 position_w = Vec3::Zero();
  Quat orientation_ws = Quat::Identity();
};

/// Mounting: nominal pose on the body and per-environment randomisation ranges (Aerial Gym's
/// randomize_placement, min/max_translation, min/max_euler_rotation_deg; Euler as in kernel/).
struct MountParams {
  Vec3 nominal_position_b = Vec3::Zero();
  Vec3 nominal_euler_deg = Vec3::Zero();  // roll, pitch, yaw
  bool randomize_placement = false;
  Vec3 min_translation_b = Vec3::Zero(), max_translation_b = Vec3::Zero();
  Vec3 min_euler_deg = Vec3::Zero(), max_euler_deg = Vec3::Zero();
};

struct Mount {
  Vec3 position_b = Vec3::Zero();
  Quat orientation_bs = Quat::Identity();
};

/// Nominal pose, or (randomize_placement) translation and Euler angles drawn uniformly within the
/// ranges from rng (use kPurposePlacement, one stream per environment). Like Aerial Gym the
/// randomised values replace the nominal ones.
Mount sample_mount(const MountParams& p, RngStream& rng);
/// World pose of a sensor mounted on a body.
SensorPose sensor_pose(const RigidBodyState& body, const Mount& m);

/// Noise applied to raw pixel values before the out-of-range rules (all from one stream; each
/// pixel consumes a fixed number of draws, so results do not depend on which pixels hit).
struct NoiseParams {
  enum class Model : std::uint8_t { none, range_dependent, multiplier };
  Model model = Model::none;
  // range_dependent: value += N(0, a r^2 + b r + c) + offset.
  real a = 0, b = 0, c = 0, offset = 0;
  // multiplier (Aerial Gym's pixel_std_dev_multiplier): value += N(0, multiplier * value).
  real std_dev_multiplier = 0.01_r;
  // Both models: a pixel drops out with this probability and reads dropout_value (no return).
  real pixel_dropout_prob = 0;
  real dropout_value = 0;
};
void apply_noise(const NoiseParams& p, real* values, std::uint32_t n, RngStream& rng);

/// Output images in caller storage (any pointer may be null; sizes = table height x width).
struct SensorOutput {
  real* range = nullptr;            // range or depth image, post-processed
  std::int32_t* segmentation = nullptr;
  real* points = nullptr;           // 3 per pixel: raw value x dir (sensor frame) or world hit point
  bool points_in_world_frame = false;
  real* normals_w = nullptr;        // 3 per pixel, world frame; zero without a hit
};

/// Casts every ray of the table from the sensor pose and writes the outputs. A dirty scene or a
/// table without rays -> invalid_argument (nothing written).
[[nodiscard]] Status render(const Scene& scene, const SensorPose& pose, const RayTable& table,
                            const RangeOutputParams& out_params, bool depth, SensorOutput& out,
                            const NoiseParams* noise = nullptr, RngStream* rng = nullptr);

}  // namespace kestrel::sensors
