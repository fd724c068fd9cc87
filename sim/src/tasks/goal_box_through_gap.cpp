// The worked custom task "goal_box_through_gap" and the tasks' registry entries.
#include <cmath>

#include "kestrel/sim/custom_task.hpp"
#include "kestrel/sim/locomotion_task.hpp"
#include "kestrel/sim/navigation_task.hpp"
#include "kestrel/sim/pick_place_task.hpp"

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
  register_locomotion_builtins(r);  // locomotion_task, its robot presets, legged_sim, legged_flat / legged_rough
  r.tasks.add("so101_pick_place",
              "LeIsaac's SO-101 pick-and-place (cube into box) over PickPlaceWorld: 31 obs, 6 joint targets (or 5 ee deltas, "
              "task.pick_place.action_mode), shaped reward, success = cube in box and released, 20 s episodes",
              [] { return pick_place_task_config(); });
  const CustomTaskSpec g = goal_box_through_gap_spec();
  r.tasks.add(g.id, g.description, [] { return custom_task_config(goal_box_through_gap_spec()); });
}

}  // namespace kestrel::sim
