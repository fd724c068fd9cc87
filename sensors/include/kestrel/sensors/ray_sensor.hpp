// Ray-pattern sensors: lidar (and the multizone ToF, which is a small lidar grid), pinhole depth
// camera, their Aerial Gym-compatible post-processing, noise and mounting.
//
// Ray tables follow tests/golden/reference/sensor_rays.json exactly:
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
// kNoHitValue) -> optional noise (dropout -> near_out_of_range_value) -> > max_range:
// far_out_of_range_value, then < min_range: near_out_of_range_value (two successive rules, as
// Aerial Gym's WarpSensor.apply_range_limits) -> optional division by max_range.
// Sensor-frame point clouds follow the same rules on the point's norm (all three components take
// the out-of-range value) and are divided by max_range when normalising; world-frame point clouds
// are left raw (Aerial Gym). Difference kept on purpose: Aerial Gym's point-cloud mode adds the
// pixel noise to each coordinate; here noise is applied to the range image only.
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

/// Mounting: nominal pose on the body and per-environment randomisation ranges (Aerial Gym's
/// randomize_placement, min/max_translation, min/max_euler_rotation_deg, nominal_position,
/// nominal_orientation_euler_deg; Euler as in kernel/).
struct MountParams {
  Vec3 nominal_position_b = Vec3::Zero();
  Vec3 nominal_euler_deg = Vec3::Zero();  // roll, pitch, yaw
  bool randomize_placement = false;
  Vec3 min_translation_b = Vec3::Zero(), max_translation_b = Vec3::Zero();
  Vec3 min_euler_deg = Vec3::Zero(), max_euler_deg = Vec3::Zero();
  // Pose used when randomize_placement is false. Aerial Gym's warp (ray-cast) sensors ignore
  // nominal_position / nominal_orientation_euler_deg (the configs say they are "only for Isaac Gym
  // Camera Sensors"): a non-randomised warp sensor sits at zero translation with the Euler angles
  // (min + max) / 2. true = that warp behaviour (all presets); false = the nominal pose (kept as
  // the default for hand-written mounts such as the firmware's).
  bool fixed_pose_at_range_mean = false;
};

/// Noise applied to raw pixel values before the out-of-range rules (all from one stream; each
/// pixel consumes a fixed number of draws, so results do not depend on which pixels hit).
/// Aerial Gym: a dropped pixel reads the sensor's near_out_of_range_value (render() passes it).
struct NoiseParams {
  enum class Model : std::uint8_t { none, range_dependent, multiplier };
  bool enable_sensor_noise = true;  // Aerial Gym sensor_noise.enable_sensor_noise
  Model model = Model::none;
  // range_dependent (Aerial Gym WarpSensor.apply_noise): value ~ N(r - mean_offset, a r^2 + b r + c)
  // (note the sign: the configs' negative mean_offset lengthens the ranges).
  real a = 0, b = 0, c = 0, mean_offset = 0;
  // multiplier (Aerial Gym's camera-config pixel_std_dev_multiplier, as its Isaac Gym camera
  // sensor applies it): value ~ N(r, multiplier * r).
  real std_dev_multiplier = 0.01_r;
  // Both models: a pixel drops out with this probability.
  real pixel_dropout_prob = 0;
};

/// What a sensor returns (Aerial Gym return_pointcloud, pointcloud_in_world_frame,
/// segmentation_camera): callers set the SensorOutput pointers accordingly.
struct OutputFlags {
  bool return_pointcloud = false;
  bool pointcloud_in_world_frame = false;
  bool segmentation_camera = true;
};

struct LidarParams {
  std::uint32_t height = 64;  // scan lines
  std::uint32_t width = 512;  // points per line
  real horizontal_fov_deg_min = -180, horizontal_fov_deg_max = 180;
  real vertical_fov_deg_min = 0, vertical_fov_deg_max = 90;
  RangeOutputParams range{0.5_r, 20, false, -1, -1};
  OutputFlags output{};
  MountParams mount{};
  NoiseParams noise{};
  // Aerial Gym's euler_frame_rot_deg is [0, 0, 0] for every lidar config: the ray frame is the
  // sensor frame (no field needed).
};

struct CameraParams {
  std::uint32_t height = 135;  // rows
  std::uint32_t width = 240;   // columns
  real horizontal_fov_deg = 87;
  bool calculate_depth = true;  // depth along the optical axis (else range along the ray)
  RangeOutputParams range{0.2_r, 10, false, -1, -1};
  OutputFlags output{};
  MountParams mount{};
  NoiseParams noise{};
  // Aerial Gym's euler_frame_rot_deg is [-90, 0, -90] for every camera config: the optical ->
  // sensor mapping (z, -x, -y) built into camera_ray() is exactly that rotation.
};

// Presets: each reproduces one Aerial Gym config class of github.com/ntnu-arl/aerial_gym_simulator
// (aerial_gym/config/sensor_config/..., file and commit named per preset), with the values the
// Python class really ends up with. Inheritance quirk kept on purpose: far/near_out_of_range_value
// are computed in the body of the class that defines them, so a subclass that changes max_range
// keeps its parent's values (e.g. OSDome: max 20 m but far = 10, near = -10; OS1/OS2: 35 / -35).
// Mount ranges: base_sensor_config.py (ad20caeca535a46b36ff716b6f8fc2470c4508c9) where inherited.
/// lidar_config/base_lidar_config.py @1e8af3cc3ce594a95eba384d9fd014f24b5f9c5c: 128 x 512,
/// h -180..180, v -45..45 deg, 0.2-10 m, normalised, segmentation, randomised mount, noise on.
LidarParams lidar_preset_base();
/// lidar_config/osdome_64_config.py @0f4463327c70fd5ece48abcc0b9e181daadc99a7: 64 x 512,
/// h -180..180, v 0..90 deg, 0.5-20 m, normalised (far 10, near -10 inherited), fixed mount.
LidarParams lidar_preset_osdome_64();
/// lidar_config/os0_128_config.py @1e8af3cc3ce594a95eba384d9fd014f24b5f9c5c: 128 x 512,
/// v -45..45 deg, 0.2-35 m, normalised (far 35, near -35).
LidarParams lidar_preset_os0_128();
/// lidar_config/os0_64_config.py @0f4463327c70fd5ece48abcc0b9e181daadc99a7: OS0-128 with 64 lines.
LidarParams lidar_preset_os0_64();
/// lidar_config/os1_64_config.py @1e8af3cc3ce594a95eba384d9fd014f24b5f9c5c: 64 x 512,
/// v -22.5..22.5 deg, 0.7-90 m (far 35, near -35 inherited from OS0-128).
LidarParams lidar_preset_os1_64();
/// lidar_config/os2_64_config.py @1e8af3cc3ce594a95eba384d9fd014f24b5f9c5c: 64 x 512,
/// v -11.25..11.25 deg, 0.7-200 m (far 35, near -35 inherited from OS0-128).
LidarParams lidar_preset_os2_64();
/// lidar_config/rslidar_airy_config.py @e2a04d4a5f384f20bc85c2a41e2511116aded9d1: 48 x 120,
/// h -180..180, v 0..90 deg, 0.2-10 m, not normalised (far 10, near -10 inherited), world-frame
/// point cloud, no segmentation, mount fixed at (-0.05, 0, 0), pitch -90 deg (min = max).
LidarParams lidar_preset_rs_airy();
/// lidar_config/pmd_flexx2_config.py @1ba60ad91635bd3e42442b50800c00aa2a868923: 172 x 224,
/// h -28..28, v -22..22 deg, 0.2-5 m, normalised, no segmentation, randomised mount.
LidarParams lidar_preset_pmd_flexx2();
/// lidar_config/st_vl53l5cx_config.py @7a77ada2a55a0804ed978d2dac7babb2c2dcd55a: 8 x 8,
/// h and v -45..45 deg, 0.2-4 m, not normalised, no segmentation, noise on (multiplier 0.02,
/// dropout 0.01).
LidarParams lidar_preset_vl53l5cx();
/// camera_config/base_depth_camera_config.py @ad20caeca535a46b36ff716b6f8fc2470c4508c9:
/// 135 x 240, hfov 87 deg, 0.2-10 m, depth, normalised, segmentation, randomised mount.
CameraParams camera_preset_base();
/// camera_config/intel_realsense_d455_config.py @83bbdbe9f6125be98161a084bdf88cc26d3436de (same
/// values as d455_depth_config.py @ad20caeca535a46b36ff716b6f8fc2470c4508c9): 270 x 480, hfov 87
/// deg, 0.2-15 m, normalised (far 15, near -15), segmentation, randomised mount.
CameraParams camera_preset_d455();
/// camera_config/luxonis_oak_d_config.py @7a77ada2a55a0804ed978d2dac7babb2c2dcd55a: 270 x 480,
/// hfov 72 deg, 0.7-12 m, normalised (far 12, near -12), no segmentation, fixed mount.
CameraParams camera_preset_oakd();
/// camera_config/luxonis_oak_d_pro_w_config.py @83bbdbe9f6125be98161a084bdf88cc26d3436de: OAK-D
/// with hfov 127 deg, 0.2-12 m.
CameraParams camera_preset_oakd_pro_w();

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

struct Mount {
  Vec3 position_b = Vec3::Zero();
  Quat orientation_bs = Quat::Identity();
};

/// randomize_placement: translation and Euler angles drawn uniformly within the ranges from rng
/// (use kPurposePlacement, one stream per environment), replacing the nominal ones like Aerial
/// Gym. Otherwise the fixed pose chosen by fixed_pose_at_range_mean (see MountParams).
Mount sample_mount(const MountParams& p, RngStream& rng);
/// World pose of a sensor mounted on a body.
SensorPose sensor_pose(const RigidBodyState& body, const Mount& m);

/// Applies p to n values; a dropped pixel reads dropout_value (Aerial Gym: the sensor's
/// near_out_of_range_value). No-op unless enable_sensor_noise and a model are set.
void apply_noise(const NoiseParams& p, real* values, std::uint32_t n, RngStream& rng, real dropout_value);

/// Output images in caller storage (any pointer may be null; sizes = table height x width).
struct SensorOutput {
  real* range = nullptr;            // range or depth image, post-processed
  std::int32_t* segmentation = nullptr;
  real* points = nullptr;           // 3 per pixel: range x dir (sensor frame, post-processed) or world hit point (raw)
  bool points_in_world_frame = false;
  real* normals_w = nullptr;        // 3 per pixel, world frame; zero without a hit
};

/// Casts every ray of the table from the sensor pose and writes the outputs. A dirty scene or a
/// table without rays -> invalid_argument (nothing written).
[[nodiscard]] Status render(const Scene& scene, const SensorPose& pose, const RayTable& table,
                            const RangeOutputParams& out_params, bool depth, SensorOutput& out,
                            const NoiseParams* noise = nullptr, RngStream* rng = nullptr);

}  // namespace kestrel::sensors
