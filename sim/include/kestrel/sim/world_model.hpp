// The rigid World's model: everything compiled once from a WorldConfig and read, never written,
// by a step (MuJoCo's mjModel). Its counterpart, WorldData (sim/world_data.hpp), holds every array
// a step writes; the stage functions (sim/world_stages.hpp) take (const WorldModel&, WorldData&).
//
// Robots are identical within a world, so one rigid-body model and one control chain
// (robots::MultirotorModel) serve every environment. Sizes: E = num_envs, R = robots_per_env,
// N = E * R robots (robot index env * R + r), C = obstacle_capacity slots per environment.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "kestrel/kernel/rigid_body.hpp"
#include "kestrel/robots/multirotor.hpp"
#include "kestrel/sensors/imu.hpp"
#include "kestrel/sensors/ray_sensor.hpp"
#include "kestrel/sim/config.hpp"

namespace kestrel::sim {

class Terrain;
struct SceneMesh;

/// One attached sensor's constant part (robot.sensors[k]): the ray table and the post-processing
/// parameters. Its per-robot outputs are WorldData::sensors[k].
struct SensorModel {
  SensorKind kind = SensorKind::camera;
  int every = 1;        // env-steps between renders
  bool depth = false;   // depth camera: ranges are depths along the optical axis
  sensors::RangeOutputParams range;
  sensors::NoiseParams noise;
  sensors::MountParams mount;
  std::vector<real> dirs_s, depth_scale;  // (pixels x 3), (pixels): the table's storage
  sensors::RayTable table;
  std::size_t pixels = 0;  // height * width (0 for an IMU)
};

struct WorldModel {
  WorldConfig cfg;  // as given (the run-time curriculum level lives in WorldData)
  int num_envs = 0;             // E
  int robots_per_env = 0;       // R
  int obstacle_capacity = 0;    // C: sum of asset_class_slots over env.assets
  std::size_t action_dim = 0;   // values the controller reads per robot (<= kMaxActionDim)
  real robot_bound_radius_m = 0;  // bounding sphere of the robot's collision shape

  RigidBodyModel body;          // mass, inertia, drag, gravity, integrator
  robots::MultirotorModel mr;   // controller -> allocation -> motors (robots/multirotor.hpp)

  std::unique_ptr<Terrain> terrain;  // shared by every environment (sim/terrain.hpp)
  int height_points = 0;             // H: measured_heights points per robot
  std::vector<real> height_points_x_b, height_points_y_b;  // (H) body-yaw-frame offsets, x-major

  std::vector<std::vector<Vec3>> mesh_vertices;             // per asset class (AssetKind::mesh): hull vertices
  std::vector<std::unique_ptr<SceneMesh>> render_meshes;    // per asset class (AssetKind::mesh): what sensors see
  bool obstacles_rotate = false;  // some asset class has max_angular_speed_rad_s > 0

  std::vector<SensorModel> sensors;  // robot.sensors, in order
  bool any_ray_sensor = false, any_imu = false;
  std::uint32_t scene_capacity = 0;  // objects per environment scene: C slots + the ground

  std::size_t index(int env, int robot) const { return static_cast<std::size_t>(env) * static_cast<std::size_t>(robots_per_env) + static_cast<std::size_t>(robot); }

  WorldModel();
  ~WorldModel();
  WorldModel(const WorldModel&) = delete;
  WorldModel& operator=(const WorldModel&) = delete;
};

/// Validates the config and compiles the model (rigid-body model, control chain, terrain, meshes,
/// sensor tables). False and a message naming the field on bad input; the model is then unusable.
[[nodiscard]] bool compile_world_model(const WorldConfig& config, WorldModel& model, std::string& error);

}  // namespace kestrel::sim
