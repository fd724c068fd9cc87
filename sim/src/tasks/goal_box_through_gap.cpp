// The worked custom task "goal_box_through_gap" and the tasks' registry entries.
#include <cmath>

#include "kestrel/sim/custom_task.hpp"
#include "kestrel/sim/locomotion_task.hpp"
#include "kestrel/sim/navigation_task.hpp"

namespace kestrel::sim {

namespace {

// Geometry (world frame, room x -4..4, y -3..3, z 0..3): the wall is the plane x = 0, 0.1 m thick
// and 4 m tall (above the room's 3.5 m out-of-bounds limit, so it cannot be flown over), made of
// two 8 m long halves whose inner edges bound the gap; both halves and the gap marker move with
// the lateral draw, the halves move apart with the width draw.
constexpr real kWallHalfLength = 4.0_r;
constexpr real kGapNominalWidth = 1.05_r;  // +- 0.15 m by the width term: 0.9 .. 1.2 m
constexpr real kPassHeight = 1.2_r;        // the scripted policy crosses the wall at this height

// Fly to a point 0.7 m in front of the gap, through it to 0.8 m behind, then down into the box.
// Stateless (the phase follows from the robot's position), so it restarts cleanly after a reset.
void goal_box_scripted(const CustomTaskSpec&, const Vec3& p, const Vec3* c, float* a) {
  const Vec3& gap = c[2];
  const Vec3& box = c[3];
  const real wall_x = gap[0];
  // The gap marker's height is the pass height (kPassHeight on rigid; the planar task gives the
  // objects at its flight altitude, where the vertical part of the targets is dropped anyway).
  const real pass_z = gap[2];
  Vec3 target;
  const bool aligned = std::fabs(p[1] - gap[1]) < 0.12_r && std::fabs(p[2] - pass_z) < 0.2_r;
  if (p[0] > wall_x + 0.4_r) target = Vec3(box[0], box[1], 0.6_r);                 // behind the wall: into the box
  else if (std::fabs(p[0] - wall_x) < 0.4_r || (aligned && p[0] > wall_x - 0.9_r))  // in or lined up: through
    target = Vec3(wall_x + 0.8_r, gap[1], pass_z);
  else target = Vec3(wall_x - 0.7_r, gap[1], pass_z);                               // line up in front of it
  Vec3 d = target - p;
  const real n = d.norm();
  if (n > 1) d /= n;  // a carrot at most 1 m ahead keeps the Lee response on the straight line
  for (int k = 0; k < 3; ++k) a[k] = static_cast<float>(d[k]);
  a[3] = 0;  // absolute yaw 0: the ToF looks along +x, at the wall
}

}  // namespace

CustomTaskSpec goal_box_through_gap_spec() {
  CustomTaskSpec s;
  s.id = "goal_box_through_gap";
  s.description = "custom task: fly through a randomised gap in a wall into a goal box (lee_position_control, ToF)";
  s.defaults.env = "goal_box_room";
  s.defaults.controller = "lee_position_control";
  s.defaults.sensors = {{"vl53l5cx", 1}};
  s.episode_len_env_steps = 1500;  // 15 s
  s.min_init_position_ratio = Vec3(0.05_r, 0.2_r, 0.3_r);  // x -3.6 .. -2.4, y -1.8 .. 1.8, z 0.9 .. 1.5 m
  s.max_init_position_ratio = Vec3(0.2_r, 0.8_r, 0.5_r);

  SceneObjectSpec left, right, gap, box;
  left.name = "wall_left";
  left.half_extents_m = Vec3(0.05_r, kWallHalfLength, 2.0_r);
  left.position_w = Vec3(0, -(kGapNominalWidth / 2 + kWallHalfLength), 2.0_r);
  left.semantic_id = 21;
  right = left;
  right.name = "wall_right";
  right.position_w[1] = -left.position_w[1];
  right.semantic_id = 22;
  gap.name = "gap";  // a marker of the gap's centre line (a region: no collision)
  gap.solid = false;
  gap.half_extents_m = Vec3(0.05_r, kGapNominalWidth / 2, 2.0_r);
  gap.position_w = Vec3(0, 0, kPassHeight);
  box.name = "goal_box";
  box.solid = false;
  box.half_extents_m = Vec3(0.5_r, 0.5_r, 0.5_r);
  box.position_w = Vec3(2.5_r, 0, 0.5_r);
  s.objects = {left, right, gap, box};

  s.observations = {{ObsTermKind::position_error_to, "gap", 0, 0},
                    {ObsTermKind::position_error_to, "goal_box", 0, 0},
                    {ObsTermKind::orientation, "", 0, 0},
                    {ObsTermKind::linear_velocity_b, "", 0, 0},
                    {ObsTermKind::angular_velocity_b, "", 0, 0},
                    {ObsTermKind::previous_actions, "", 0, 0},
                    {ObsTermKind::image_pool, "", 4, 4}};
  s.terminations = {{TerminationKind::inside_box, "goal_box", 1.0_r},
                    {TerminationKind::crash, "", 0},
                    {TerminationKind::timeout, "", 0}};
  s.rewards = {{RewardKind::progress_to, "goal_box", 1.0f},
               {RewardKind::success, "", 10.0f},
               {RewardKind::crash, "", -10.0f},
               {RewardKind::action_rate, "", -0.01f}};
  RandomizationTerm lateral;
  lateral.name = "gap_lateral";
  lateral.objects = {"wall_left", "wall_right", "gap"};
  lateral.min_offset_m = Vec3(0, -1.2_r, 0);
  lateral.max_offset_m = Vec3(0, 1.2_r, 0);
  RandomizationTerm width;
  width.name = "gap_width";
  width.objects = {"wall_left", "wall_right"};
  width.gains = {Vec3(0, -1, 0), Vec3(0, 1, 0)};
  width.min_offset_m = Vec3(0, -0.075_r, 0);
  width.max_offset_m = Vec3(0, 0.075_r, 0);
  RandomizationTerm goal;
  goal.name = "goal_box_lateral";
  goal.objects = {"goal_box"};
  goal.min_offset_m = Vec3(0, -1.5_r, 0);
  goal.max_offset_m = Vec3(0, 1.5_r, 0);
  s.randomizations = {lateral, width, goal};
  s.action_clip_m = 1.0f;
  s.scripted = goal_box_scripted;
  return s;
}

void register_task_builtins(Registries& r) {
  r.envs.add("goal_box_room", "8 x 6 x 3 m room, no obstacles of its own (goal_box_through_gap adds its wall)", [] {
    EnvConfig e;
    e.name = "goal_box_room";
    e.lower_bound_min_m = e.lower_bound_max_m = Vec3(-4, -3, 0);
    e.upper_bound_min_m = e.upper_bound_max_m = Vec3(4, 3, 3);
    return e;
  });
  r.tasks.add("navigation_task",
              "Aerial Gym's navigation RL task: velocity actions, goal in the bounds, 17 + 8x8 pooled range image obs, "
              "obstacle curriculum, success rate",
              [] { return navigation_task_config(); });
  r.tasks.add("locomotion_task",
              "legged_gym's locomotion RL task: joint targets, velocity commands, 48 obs (+ height points), legged_gym's "
              "reward terms, base-contact termination, pushes",
              [] { return locomotion_task_config(); });
  // locomotion_task with each robot's reward configuration (scenario `task: locomotion_go2`, the
  // gymnasium ids Kestrel-Go2-*-v0 / Kestrel-AnymalC-*-v0).
  r.tasks.add("locomotion_go2",
              "locomotion_task with LeggedGym-Ex's Go2 rewards (go2_config.py; its action_smoothness and foot_clearance "
              "terms are not legged_gym's and are left out) over legged_gym's command ranges",
              [] {
                TaskConfig t = locomotion_task_config();
                LocomotionConfig& l = t.locomotion;
                l.soft_dof_pos_limit = 0.9_r;
                l.base_height_target_m = 0.36_r;
                LocomotionRewardScales& s = l.scales;
                s.dof_pos_limits = -1;
                s.collision = -1;
                s.tracking_lin_vel = 1;
                s.tracking_ang_vel = 0.5_r;
                s.lin_vel_z = -0.5_r;
                s.base_height = -2;
                s.ang_vel_xy = -0.05_r;
                s.orientation = -1;
                s.dof_vel = -5e-4_r;
                s.dof_acc = -2e-7_r;
                s.action_rate = -0.01_r;
                s.torques = -2e-4_r;
                s.feet_air_time = 1;
                return t;
              });
  r.tasks.add("locomotion_anymal_c_rough", "locomotion_task with legged_gym's anymal_c_rough_config rewards", [] {
    TaskConfig t = locomotion_task_config();
    t.locomotion.base_height_target_m = 0.5_r;
    t.locomotion.max_contact_force_N = 500;
    return t;
  });
  r.tasks.add("locomotion_anymal_c_flat",
              "locomotion_task with legged_gym's anymal_c_flat_config: rewards, no heading command, yaw rate +-1.5 rad/s "
              "resampled every 4 s",
              [] {
                TaskConfig t = locomotion_task_config();
                LocomotionConfig& l = t.locomotion;
                l.base_height_target_m = 0.5_r;
                l.max_contact_force_N = 350;
                l.heading_command = false;
                l.resampling_time_s = 4;
                l.ang_vel_yaw_min_rad_s = -1.5_r;
                l.ang_vel_yaw_max_rad_s = 1.5_r;
                l.scales.orientation = -5;
                l.scales.torques = -2.5e-5_r;
                l.scales.feet_air_time = 2;
                return t;
              });
  // legged_gym's dt 5 ms with 10 constraint-solver sweeps at most (PhysX there: 4 position
  // iterations). A jittering random policy on Go2: 34k env-steps/s on 2 threads against 13k at the
  // default 60 sweeps, with the same falls and mean base speed (warm-started rows converge in a
  // few sweeps; the cap only cuts the rest short).
  r.sims.add("legged_sim", "dt 0.005 s, 10 constraint-solver sweeps (articulated robots)", [] {
    SimParams s;
    s.name = "legged_sim";
    s.dt_s = 0.005_r;
    s.solver_iterations = 10;
    return s;
  });
  // legged_gym's ground for locomotion_task: dt 5 ms (legged_sim) x decimation 4 = a 50 Hz policy.
  r.envs.add("legged_flat", "legged_gym's flat ground: plane, decimation 4 (50 Hz policy at fast_sim's 5 ms)", [] {
    EnvConfig e;
    e.name = "legged_flat";
    e.num_physics_steps_per_env_step_mean = 4;
    return e;
  });
  r.envs.add("legged_rough", "legged_gym's random_uniform rough ground (+-3 cm, 40 x 40 m), decimation 4, the 187 height points", [] {
    EnvConfig e;
    e.name = "legged_rough";
    e.num_physics_steps_per_env_step_mean = 4;
    e.terrain.type = TerrainType::heightfield;
    e.terrain.procedural = "random_uniform";
    e.terrain.length_x_m = 40;
    e.terrain.width_y_m = 40;
    e.terrain.horizontal_scale_m = 0.1_r;
    e.terrain.min_height_m = -0.03_r;
    e.terrain.max_height_m = 0.03_r;
    e.terrain.height_step_m = 0.005_r;
    e.terrain.downsampled_scale_m = 0.25_r;
    e.terrain.measure_heights = true;
    return e;
  });
  const CustomTaskSpec g = goal_box_through_gap_spec();
  r.tasks.add(g.id, g.description, [] { return custom_task_config(goal_box_through_gap_spec()); });
}

}  // namespace kestrel::sim
