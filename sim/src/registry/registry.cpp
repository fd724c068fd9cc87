// Built-in sims, environments, robots, controllers and tasks. Environment layouts follow Aerial
// Gym's env configs (empty_env, env_with_obstacles, forest_env, dynamic_env) in spirit and scale
// (env_with_obstacles: ~45 obstacles), not in every number.
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/articulated_robot.hpp"
#include "kestrel/sim/custom_task.hpp"
#include "kestrel/sim/task.hpp"
#include "kestrel/sim/simulator.hpp"

#include <cmath>

namespace kestrel::sim {

namespace {

AssetClass asset(const char* name, AssetKind kind, int n, int semantic, Vec3 min_size, Vec3 max_size) {
  AssetClass c;
  c.name = name;
  c.kind = kind;
  c.num_assets = n;
  c.min_num_assets = n / 4;
  c.semantic_id = semantic;
  c.min_size_m = min_size;
  c.max_size_m = max_size;
  return c;
}

// An obstacle class of the planar yard: upright, yaw only, in the middle band of the yard.
AssetClass yard_asset(const char* name, AssetKind kind, int n, int semantic, real min_size, real max_size) {
  AssetClass c = asset(name, kind, n, semantic, Vec3::Constant(min_size), Vec3::Constant(max_size));
  c.min_num_assets = n / 2;
  c.min_position_ratio = Vec3(0.3_r, 0.05_r, 0.5_r);
  c.max_position_ratio = Vec3(0.7_r, 0.95_r, 0.5_r);
  c.max_euler_rad = Vec3(0, 0, kPi);  // yaw only: planar boxes
  return c;
}

EnvConfig obstacle_env(const char* name) {
  EnvConfig e;
  e.name = name;
  e.lower_bound_min_m = Vec3(-6, -6, 0);
  e.lower_bound_max_m = Vec3(-5, -5, 0);
  e.upper_bound_min_m = Vec3(5, 5, 4);
  e.upper_bound_max_m = Vec3(6, 6, 5);
  AssetClass walls = asset("walls", AssetKind::wall, 5, 8, Vec3::Zero(), Vec3::Zero());
  walls.keep_in_env = true;
  walls.min_num_assets = 5;
  e.assets.push_back(walls);
  AssetClass panels = asset("panels", AssetKind::panel, 20, 1, Vec3(0, 0.8_r, 1.0_r), Vec3(0, 1.6_r, 2.5_r));
  panels.min_position_ratio = Vec3(0.3_r, 0.05_r, 0.1_r);
  panels.max_position_ratio = Vec3(0.85_r, 0.95_r, 0.9_r);
  panels.max_euler_rad = Vec3(0, 0, kPi);
  e.assets.push_back(panels);
  AssetClass cubes = asset("objects", AssetKind::cube, 8, 2, Vec3::Constant(0.3_r), Vec3::Constant(0.8_r));
  cubes.min_position_ratio = Vec3(0.3_r, 0.05_r, 0.05_r);
  cubes.max_position_ratio = Vec3(0.85_r, 0.95_r, 0.95_r);
  cubes.max_euler_rad = Vec3(kPi, kPi, kPi);
  e.assets.push_back(cubes);
  AssetClass rods = asset("rods", AssetKind::rod, 6, 3, Vec3(0.03_r, 0, 0.8_r), Vec3(0.08_r, 0, 2.0_r));
  rods.min_position_ratio = Vec3(0.3_r, 0.05_r, 0.1_r);
  rods.max_position_ratio = Vec3(0.85_r, 0.95_r, 0.9_r);
  rods.max_euler_rad = Vec3(kPi / 2, kPi / 2, 0);
  e.assets.push_back(rods);
  AssetClass small_walls = asset("small_walls", AssetKind::small_wall, 6, 4, Vec3(0, 0.5_r, 0.5_r), Vec3(0, 1.2_r, 1.2_r));
  small_walls.min_position_ratio = Vec3(0.3_r, 0.05_r, 0.1_r);
  small_walls.max_position_ratio = Vec3(0.85_r, 0.95_r, 0.9_r);
  small_walls.max_euler_rad = Vec3(0, 0, kPi);
  e.assets.push_back(small_walls);
  return e;
}

SensorConfig lidar_sensor(const char* name, const sensors::LidarParams& p) {
  SensorConfig c;
  c.name = name;
  c.kind = SensorKind::lidar;
  c.lidar = p;
  return c;
}
SensorConfig camera_sensor(const char* name, const sensors::CameraParams& p) {
  SensorConfig c;
  c.name = name;
  c.kind = SensorKind::camera;
  c.camera = p;
  return c;
}
SensorConfig imu_sensor(const char* name, const sensors::ImuParams& p) {
  SensorConfig c;
  c.name = name;
  c.kind = SensorKind::imu;
  c.imu = p;
  return c;
}

// The sensor presets of kestrel/sensors (each reproduces one Aerial Gym sensor config class).
void register_sensors(Registry<SensorConfig>& s) {
  namespace ks = kestrel::sensors;
  s.add("base_lidar", "lidar 128 x 512, v -45..45 deg, 0.2-10 m", [] { return lidar_sensor("base_lidar", ks::lidar_preset_base()); });
  s.add("osdome_64", "Ouster OSDome lidar 64 x 512, v 0..90 deg, 0.5-20 m", [] { return lidar_sensor("osdome_64", ks::lidar_preset_osdome_64()); });
  s.add("os0_128", "Ouster OS0 lidar 128 x 512, v -45..45 deg, 0.2-35 m", [] { return lidar_sensor("os0_128", ks::lidar_preset_os0_128()); });
  s.add("os0_64", "Ouster OS0 lidar 64 x 512", [] { return lidar_sensor("os0_64", ks::lidar_preset_os0_64()); });
  s.add("os1_64", "Ouster OS1 lidar 64 x 512, v -22.5..22.5 deg, 0.7-90 m", [] { return lidar_sensor("os1_64", ks::lidar_preset_os1_64()); });
  s.add("os2_64", "Ouster OS2 lidar 64 x 512, v -11.25..11.25 deg, 0.7-200 m", [] { return lidar_sensor("os2_64", ks::lidar_preset_os2_64()); });
  s.add("rs_airy", "RoboSense Airy lidar 48 x 120, hemisphere, pitched down", [] { return lidar_sensor("rs_airy", ks::lidar_preset_rs_airy()); });
  s.add("pmd_flexx2", "pmd flexx2 ToF 172 x 224, 56 x 44 deg, 0.2-5 m", [] { return lidar_sensor("pmd_flexx2", ks::lidar_preset_pmd_flexx2()); });
  s.add("vl53l5cx", "ST VL53L5CX multizone ToF 8 x 8, 90 x 90 deg, 0.2-4 m", [] { return lidar_sensor("vl53l5cx", ks::lidar_preset_vl53l5cx()); });
  s.add("base_depth_camera", "depth camera 135 x 240, hfov 87 deg, 0.2-10 m", [] { return camera_sensor("base_depth_camera", ks::camera_preset_base()); });
  s.add("d455", "Intel RealSense D455 depth 270 x 480, hfov 87 deg, 0.2-15 m", [] { return camera_sensor("d455", ks::camera_preset_d455()); });
  s.add("oakd", "Luxonis OAK-D depth 270 x 480, hfov 72 deg, 0.7-12 m", [] { return camera_sensor("oakd", ks::camera_preset_oakd()); });
  s.add("oakd_pro_w", "Luxonis OAK-D Pro W depth 270 x 480, hfov 127 deg, 0.2-12 m", [] { return camera_sensor("oakd_pro_w", ks::camera_preset_oakd_pro_w()); });
  s.add("base_imu", "IMU (Aerial Gym base_imu_config)", [] { return imu_sensor("base_imu", ks::imu_preset_base()); });
  s.add("vn100", "VectorNav VN-100 IMU", [] { return imu_sensor("vn100", ks::imu_preset_vn100()); });
  s.add("bmi088", "Bosch BMI088 IMU", [] { return imu_sensor("bmi088", ks::imu_preset_bmi088()); });
}

// The backends and the planar presets (a yard for both backends, the car for planar).
void register_simulators(Registries& r) {
  r.simulators.add("rigid", "3-D World: Newton-Euler bodies, libccd/analytic collision, penalty contact (default)", [] {
    SimulatorConfig c;
    c.backend = "rigid";
    return c;
  });
  r.simulators.add("planar", "Box2D 2.4 plane: ground vehicle (velocity + steering, bicycle model) or fixed-altitude multirotor",
                   [] {
                     SimulatorConfig c;
                     c.backend = "planar";
                     return c;
                   });
  r.envs.add("planar_obstacles", "12 x 12 m yard: bounding walls, 8 round pillars, 6 yaw-rotated boxes (planar or rigid)", [] {
    EnvConfig e;
    e.name = "planar_obstacles";
    e.lower_bound_min_m = Vec3(-6, -6, 0);
    e.lower_bound_max_m = Vec3(-6, -6, 0);
    e.upper_bound_min_m = Vec3(6, 6, 2);
    e.upper_bound_max_m = Vec3(6, 6, 2);
    AssetClass walls = yard_asset("walls", AssetKind::wall, 5, 8, 0, 0);
    walls.keep_in_env = true;
    walls.min_num_assets = 5;
    e.assets.push_back(walls);
    AssetClass pillars = yard_asset("pillars", AssetKind::thin, 8, 6, 0.15_r, 0.35_r);
    pillars.min_size_m[2] = pillars.max_size_m[2] = 2;  // full height (a cylinder of 2 m on rigid)
    e.assets.push_back(pillars);
    e.assets.push_back(yard_asset("boxes", AssetKind::cube, 6, 2, 0.4_r, 0.9_r));
    return e;
  });
  // Legged robots from the model files of models/ (read when the simulator is built), with
  // legged_gym's joint drives: LeggedGym-Ex's Go2 (stiffness 20, damping 0.5, action scale 0.25)
  // and legged_gym's ANYmal C (80, 2, 0.5).
  auto legged = [](const char* name, const char* file, real kp, real kd, real scale) {
    return [=] {
      RobotConfig c;
      c.name = name;
      c.kind = robots::RobotKind::articulated;
      c.model_file = models_dir() + file;
      c.joint_kp_Nm_rad = kp;
      c.joint_kd_Nms_rad = kd;
      c.action_scale = scale;
      return c;
    };
  };
  r.robots.add("go2", "Unitree Go2 quadruped (articulated, 12 joints, 15.0 kg): models/go2/go2.xml",
               legged("go2", "/go2/go2.xml", 20, 0.5_r, 0.25_r));
  r.robots.add("anymal_c", "ANYbotics ANYmal C quadruped (articulated, 12 joints, 52.1 kg): models/anymal_c/anymal_c.xml",
               legged("anymal_c", "/anymal_c/anymal_c.xml", 80, 2, 0.5_r));
  r.robots.add("ground_vehicle", "car-like robot (planar only): 3.5 kg, wheelbase 0.33 m, box 0.5 x 0.3 m", [] {
    RobotConfig c;
    c.name = "ground_vehicle";
    c.kind = robots::RobotKind::ground_vehicle;
    c.mass_kg = 3.5_r;
    c.inertia_diag_kg_m2 = Vec3(0.03_r, 0.08_r, 0.1_r);
    c.shape.type = ShapeType::box;
    c.shape.half_extents_m = Vec3(0.25_r, 0.15_r, 0.1_r);
    c.min_init_position_ratio = Vec3(0.05_r, 0.1_r, 0);
    c.max_init_position_ratio = Vec3(0.2_r, 0.9_r, 0);
    // Starts facing into the yard (+-90 deg of +x): a car cannot turn on the spot, and a U-turn
    // (radius L / tan(0.4) = 0.78 m plus the body) next to the start wall often hits it.
    c.max_init_yaw_rad = kPi / 2;
    return c;
  });
}

}  // namespace

// Long on purpose: the table of built-in presets, one entry per line (Crazyflie's and MuJoCo's
// habit for registries); splitting it would scatter the table, not simplify it.
void register_builtins(Registries& r) {
  register_sensors(r.sensors);
  register_simulators(r);  // rigid, planar and the planar presets (below)
  r.sims.add("base_sim", "dt 0.01 s, 1 substep, gravity (0, 0, -9.81)", [] { return SimParams(); });
  r.sims.add("fast_sim", "dt 0.005 s, 1 substep", [] {
    SimParams s;
    s.name = "fast_sim";
    s.dt_s = 0.005_r;
    return s;
  });
  r.sims.add("falling_forwards", "gravity tilted forwards: (4.905, 0, -8.496) m/s^2 (30 deg)", [] {
    SimParams s;
    s.name = "falling_forwards";
    s.gravity_w = Vec3(kStandardGravity * 0.5_r, 0, -kStandardGravity * std::sqrt(0.75_r));
    return s;
  });

  r.envs.add("empty", "no obstacles, ground plane, bounds +-5 m x 5 m", [] { return EnvConfig(); });
  r.envs.add("env_with_obstacles", "5 bounding walls, 20 panels, 8 objects, 6 rods, 6 small walls (~45)",
             [] { return obstacle_env("env_with_obstacles"); });
  r.envs.add("forest", "10 procedural trees (capsule trunk + 3 branches each)", [] {
    EnvConfig e;
    e.name = "forest";
    e.lower_bound_min_m = Vec3(-6, -4, 0);
    e.lower_bound_max_m = Vec3(-6, -4, 0);
    e.upper_bound_min_m = Vec3(6, 4, 5);
    e.upper_bound_max_m = Vec3(6, 4, 5);
    AssetClass trees = asset("trees", AssetKind::tree, 10, 5, Vec3(0.08_r, 1.0_r, 3.0_r), Vec3(0.2_r, 1.8_r, 5.0_r));
    trees.min_position_ratio = Vec3(0.3_r, 0.05_r, 0);
    trees.max_position_ratio = Vec3(0.7_r, 0.95_r, 0);
    e.assets.push_back(trees);
    return e;
  });
  r.envs.add("lidar_navigation", "panels, thin poles and objects for lidar navigation (~35)", [] {
    EnvConfig e = obstacle_env("lidar_navigation");
    e.assets.erase(e.assets.begin());  // no bounding walls: open sides
    AssetClass thin = asset("thin", AssetKind::thin, 10, 6, Vec3(0.02_r, 0, 2.0_r), Vec3(0.05_r, 0, 4.0_r));
    thin.min_position_ratio = Vec3(0.3_r, 0.05_r, 0.5_r);
    thin.max_position_ratio = Vec3(0.85_r, 0.95_r, 0.5_r);
    e.assets.push_back(thin);
    return e;
  });
  r.envs.add("dynamic", "env_with_obstacles whose objects move at up to 1 m/s, spin at up to 1 rad/s per axis and bounce off the bounds", [] {
    EnvConfig e = obstacle_env("dynamic");
    for (AssetClass& c : e.assets)
      if (c.kind != AssetKind::wall) {
        c.max_speed_m_s = 1;
        c.max_angular_speed_rad_s = 1;  // per-reset random angular velocity (World::move_obstacles)
      }
    return e;
  });

  r.robots.add("base_quadrotor", "Aerial Gym base quadrotor: 0.25 kg, 4 x [0, 2] N, sphere r 0.2 m", [] { return RobotConfig(); });
  r.robots.add("x500", "Holybro X500 class quad: 2.0 kg, 4 x [0, 10] N, sphere r 0.35 m", [] {
    RobotConfig c;
    c.name = "x500";
    c.airframe = allocation::AirframePreset::x500;
    c.mass_kg = 2.0_r;
    c.inertia_diag_kg_m2 = Vec3(0.0217_r, 0.0217_r, 0.04_r);
    c.shape.radius_m = 0.35_r;
    return c;
  });
  r.robots.add("hexarotor", "hex-X, 2.4 kg, 6 x [0, 8] N, sphere r 0.4 m", [] {
    RobotConfig c;
    c.name = "hexarotor";
    c.airframe = allocation::AirframePreset::hexarotor;
    c.mass_kg = 2.4_r;
    c.inertia_diag_kg_m2 = Vec3(0.03_r, 0.03_r, 0.055_r);
    c.shape.radius_m = 0.4_r;
    return c;
  });

  for (std::size_t k = 0; k < kNumControllerKinds; ++k) {
    const ControllerKind kind = static_cast<ControllerKind>(k);
    if (kind == ControllerKind::rov_fully_actuated) continue;  // needs a fully actuated robot
    // No robot kind with joints yet (the articulated-robots issue): joint_pd_control is the core
    // table's (control_update), not a scenario's.
    if (controller_family(kind) == ControlFamily::articulated) continue;
    const std::string name = controller_name(kind);
    r.controllers.add(name, "core controller " + name, [kind, name] {
      ControllerConfig c;
      c.name = name;
      c.kind = kind;
      return c;
    });
  }

  r.tasks.add("position_setpoint", "fly to a target drawn per episode; success = within 0.3 m at timeout", [] { return TaskConfig(); });
  r.tasks.add("position_setpoint_task",
               "Aerial Gym's RL task: 13 obs, 4 actions, its reward (-20 on crash or d > 8 m); run through sim/task.hpp",
               [] { return position_setpoint_task_config(); });
  r.tasks.add("hover", "hold the start position", [] {
    TaskConfig t;
    t.name = "hover";
    t.kind = TaskKind::hover;
    return t;
  });
  r.tasks.add("joint_targets",
               "articulated robots: random joint targets about the home pose (kestrel run); an episode ends on a base "
               "contact or at its timeout",
               [] {
                 TaskConfig t;
                 t.name = "joint_targets";
                 t.kind = TaskKind::hover;
                 t.episode_len_env_steps = 1000;  // legged_gym's 20 s at 50 Hz
                 return t;
               });
  register_task_builtins(r);  // navigation_task, goal_box_through_gap and its room (sim/src/tasks/)
}

Registries& registries() {
  static Registries r = [] {
    Registries x;
    register_builtins(x);
    return x;
  }();
  return r;
}

}  // namespace kestrel::sim
