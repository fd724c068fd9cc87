// The stages of one env-step of the rigid World, as free functions over (const WorldModel&,
// WorldData&, env): MuJoCo's mj_step split into named stages (mj_fwdPosition, mj_fwdVelocity, ...),
// here per environment because environments never read each other. World::step runs env_step
// over a static partition of environments on its thread pool; a binding, a viewer or a test may
// run a stage on one environment directly. None allocates.
//
//   env_step(env)
//     env_step_begin        crash flags cleared; moving setpoints advanced (episode.hpp's rule)
//     physics_step x n      (n = data.phys_steps[env]; the new action arrives at data.latency[env])
//       robot_dynamics      observation noise -> robots::multirotor_step -> wrench + contact +
//                           disturbance -> step_rigid_body (substeps)   [batched twin: 4 envs]
//       update_imus         IMU model per robot
//       physics_step_tail   move_obstacles, collide_robots (broad phase, narrow phase, terrain,
//                           penalty contact -> forces for the next physics step)
//     env_step_end          statistics, episode end (episode.hpp), auto-reset, sensors at their
//                           rate, measured heights
//
// reset_env draws an episode: bounds, a layout every keep_same_env_for_num_episodes episodes
// (generate_layout), physics steps and latency, clear start/target pairs, the chain's reset.
#pragma once

#include "kestrel/sim/world_data.hpp"
#include "kestrel/sim/world_model.hpp"

namespace kestrel::sim {
namespace batch {
struct Models;
}

namespace stage {

/// The height of an environment's ground plane (when the world has one): its floor where that lies
/// below 0, else z = 0. Collision, sensing and the batched path all use this one rule.
inline real ground_plane_z(const WorldData& d, int env) { return d.lower_w[env][2] < 0 ? d.lower_w[env][2] : real(0); }
/// Whether each env-step moves the position setpoint towards the target (TaskConfig::setpoint_speed_m_s).
inline bool moves_setpoint(const WorldModel& m) {
  return m.cfg.task.setpoint_speed_m_s > 0 && m.cfg.task.kind == TaskKind::position_setpoint &&
         m.cfg.controller.kind == ControllerKind::lee_position;
}

// Episode set-up (sim/src/engine/reset.cpp).
void reset_env(const WorldModel& m, WorldData& d, int env);
void generate_layout(const WorldModel& m, WorldData& d, int env, RngStream& rng);
/// Placement tests: a sphere / swept sphere of the robot's bound radius plus task.clearance_m
/// clears the terrain and every obstacle of env.
bool clear_point(const WorldModel& m, const WorldData& d, int env, const Vec3& p);
bool clear_segment(const WorldModel& m, const WorldData& d, int env, const Vec3& a, const Vec3& b);

// One env-step (sim/src/engine/step.cpp).
void env_step(const WorldModel& m, WorldData& d, int env);
void env_step_begin(const WorldModel& m, WorldData& d, int env);
void physics_step(const WorldModel& m, WorldData& d, int env, bool use_new_action);
void robot_dynamics(const WorldModel& m, WorldData& d, int env, std::size_t robot_index, bool use_new_action);
void physics_step_tail(const WorldModel& m, WorldData& d, int env);
void move_obstacles(const WorldModel& m, WorldData& d, int env);
void collide_robots(const WorldModel& m, WorldData& d, int env);
void env_step_end(const WorldModel& m, WorldData& d, int env);

// The batched twin over groups of batch::lanes() environments (sim/src/engine/step_batched.cpp).
bool batch_eligible(const WorldModel& m);
/// Steps environments [begin, end) by one env-step in groups; returns the first environment it
/// left to the scalar path (the tail shorter than a group).
int env_steps_batched(const WorldModel& m, WorldData& d, int begin, int end);
/// Whether env_steps_fused may run this world: the batched path's worlds whose env-steps can be
/// quiet (one sphere robot over the ground plane, no moving setpoint, no IMU, heights or ray sensor).
bool fused_eligible(const WorldModel& m);
/// Steps environments [begin, end) by num_env_steps env-steps, one lane group after the other:
/// each group takes its env-steps through batch::robot_env_steps while all of its environments'
/// env-steps are quiet (nothing but physics in flight and the tracking error), and one at a time
/// through env_steps_batched otherwise; the tail shorter than a group goes through env_step. The
/// same bits as num_env_steps calls of the step by step path (environments are independent).
void env_steps_fused(const WorldModel& m, WorldData& d, int begin, int end, int num_env_steps);

// Sensing (sim/src/engine/sensing.cpp).
void update_imus(const WorldModel& m, WorldData& d, int env, int robot, const Vec3& linvel_before_w);
/// Renders the ray sensors due at this env-step (all: every ray sensor) against env's scene.
void render_ray_sensors(const WorldModel& m, WorldData& d, int env, bool all);
void update_scene(const WorldModel& m, WorldData& d, int env);
void update_measured_heights(const WorldModel& m, WorldData& d, int env);
/// After obstacle shapes of env were rewritten: bounding boxes, sweep order, images.
void obstacles_changed(const WorldModel& m, WorldData& d, int env);

/// Puts an environment's obstacles in the broad phase's sweep order (aabb_min_w.x).
void sort_sweep_order(Obstacle* o, int n);

}  // namespace stage
}  // namespace kestrel::sim
