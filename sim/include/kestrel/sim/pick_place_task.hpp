// so101_pick_place: LeIsaac's SO-101 "pick up the cube and place it into the box" task
// (LightwheelAI/leisaac) as an RL task over N PickPlaceWorld environments (sim/pick_place.hpp),
// one per environment, seeded (seed, global env index) and stepped in the thread pool, so results
// are bit-identical for any thread count. No heap inside step() or scripted_actions().
//
// How it fits the Task interface: a Task subclass that owns its worlds through a small Simulator
// of its own (sim/src/tasks/pick_place_task.cpp). The Task base, `kestrel run`, the Python Task
// and the gymnasium env all hold a Task and read its Simulator (simulator(), backend name, thread
// count, state hash, summary, the joint views), so the worlds sit behind a Simulator whose action
// is the six joint targets and whose views are the arm's (dof_pos, dof_vel; base_pos_w = the tool
// centre point, which `kestrel run` traces); the task reaches the worlds directly for what the
// narrow Simulator API has no words for (cube, box, grip force, IK). A full backend (a third
// Backend, make_simulator, scenario `simulator:`) would be more code for nothing a caller needs:
// the task id alone selects the scene (registry, scenario `task:`, kestrel.make_vec).
//
// Observations (31 floats), LeIsaac's policy terms plus two a state-based learner needs (LeIsaac's
// policy sees the wrist and front camera images instead of the object positions):
//   [0, 6)   joint positions (rad): shoulder_pan, shoulder_lift, elbow_flex, wrist_flex, wrist_roll, gripper
//   [6, 12)  joint velocities (rad/s)
//   [12, 18) last actions: the joint targets the last action applied (after clamping into the joint
//            ranges; in ee_delta mode the IK's targets), the home pose after a reset
//   [18, 21) end-effector (gripper_frame) position (m, world = robot base frame)
//   [21, 25) end-effector orientation, quaternion xyzw (w >= 0)
//   [25, 28) cube centre - end effector (m, world frame)
//   [28, 31) box centre (its floor's bottom face) - cube centre (m, world frame)
// Actions (task.pick_place.action_mode):
//   joint_position (6): absolute joint targets (rad), LeIsaac's joint position action; clamped into
//     the joint ranges (the action space's bounds), a non-finite one holds the previous target.
//   ee_delta (5): tool-centre-point position delta (m, world, each clipped to +-ee_max_delta_m), yaw
//     delta (rad, clipped to +-ee_max_yaw_delta_rad), gripper target (rad); the task keeps a tcp
//     target (position, yaw; pointing straight down) per environment, moves it by the deltas and
//     solves it by PickPlaceWorld::solve_tcp (damped least squares) from the current targets.
// Reward: LeIsaac's task is for imitation learning (teleoperated demonstrations) and has no reward;
// this is a simple shaped one, per action step (pick_place_reward below):
//   reach   = reach_weight (1 - tanh(|cube - tcp| / reach_scale_m))
//   grasp   = grasp_weight                                  while grip force > grasp_force_N
//   lift    = lift_weight clip(h / lift_height_m, 0, 1)     while grasped (h: cube height above rest)
//   place   = place_weight (1 - tanh(|cube - box|_xy / place_scale_m))  while grasped and h > 1 cm, or in the box
//   success = success_reward                                on the step that succeeds
// Termination: success, i.e. LeIsaac's cube_in_box with the cube released (the pads' force below
// release_force_N) for success_hold_steps consecutive actions (terminated; TaskInfos::successes;
// task.pick_place.end_on_success false turns it off, bonus included, for callers with their own);
// truncation at task.episode_len_env_steps (1000 = 20 s at 50 Hz). No failure termination.
// scripted_actions(): ScriptedPickPlace per environment (restarted at every reset); idempotent
// within a step (the script advances once per task step, whichever number of calls).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "kestrel/sim/pick_place.hpp"
#include "kestrel/sim/task.hpp"

namespace kestrel::sim {

constexpr int kPickPlaceObsDim = 31;
constexpr int kPickPlaceJointActionDim = 6;
constexpr int kPickPlaceEeActionDim = 5;

enum class PickPlaceTerm : int { reach = 0, grasp, lift, place, success, count };
constexpr int kNumPickPlaceTerms = static_cast<int>(PickPlaceTerm::count);
const char* pick_place_term_name(int term);

/// What the reward reads of one environment after a step.
struct PickPlaceRewardInputs {
  float tcp_w[3] = {0, 0, 0};
  float cube_w[3] = {0, 0, 0};
  float box_w[3] = {0, 0, 0};
  float grip_force_N = 0;
  bool in_box = false;   // cube_in_box
  bool success = false;  // the step that succeeds
};
/// The shaped reward's terms (weighted; kNumPickPlaceTerms values into `terms`) and their sum.
float pick_place_reward(const PickPlaceRewardInputs& in, const PickPlaceTaskConfig& c, float* terms);

/// Builds so101_pick_place over config (task.pick_place, task.episode_len_env_steps, env.num_envs,
/// seed, threads, env.first_env_index). nullptr and a message on a bad config.
std::unique_ptr<Task> make_pick_place_task(const WorldConfig& config, std::string& error);
/// The registered config (registries().tasks "so101_pick_place"): 1000 env-steps (20 s at 50 Hz).
TaskConfig pick_place_task_config();
/// The scene's PickPlaceConfig from the task section.
PickPlaceConfig pick_place_world_config(const PickPlaceTaskConfig& c);
/// The worlds of a task built by make_pick_place_task (nullptr for any other task): for tests and
/// viewers; env in [0, num_envs).
const PickPlaceWorld* pick_place_world(const Task& task, int env);

enum class PickPlaceObject : int { cube = 0, box = 1 };
/// Moves environment env's cube (PickPlaceWorld::set_cube_pose: at rest) or box
/// (PickPlaceWorld::set_box_position: quat_xyzw not read) between steps, as an event term of a
/// Python scene task does after a reset: the Simulator's views, env's observation row, its scripted
/// controller (restarted: it plans from the objects' positions) and its success counter follow.
/// False and a message for another task, a bad env or non-finite numbers.
bool pick_place_set_object_pose(Task& task, int env, PickPlaceObject object, const Vec3& p_w, const Vec4& quat_xyzw,
                                std::string& error);

}  // namespace kestrel::sim
