// Custom tasks built from terms, registered under an id string (the LeIsaac pattern: LeRobot +
// IsaacLab manager-based tasks, where a task is a scene + a robot + observation, termination,
// reward and event (randomisation) terms, and gym.register(id=...) makes it runnable by name).
//
// A CustomTaskSpec is plain data:
//   - scene: the task's default sim/env/robot/controller/sensors (TaskDefaults, registry names),
//     plus named objects: solid ones become obstacles of every environment (in slots the task
//     owns), non-solid ones are regions (a goal box) that only terms read;
//   - observation terms, concatenated in order: position error to a named object (vehicle frame),
//     orientation quaternion xyzw, body linear / angular velocity, previous actions, the min-pooled
//     image of the robot's first ray sensor;
//   - termination terms: robot inside a named box region (its x / y ranges and a height threshold
//     above its bottom; a success), crash (contact or out of bounds; a failure), timeout (the
//     episode length; a truncation);
//   - reward terms with weights: progress towards an object, distance to it, success bonus, crash
//     penalty, action rate, alive;
//   - randomisation terms applied at every reset: one uniform draw u in [min_offset, max_offset]
//     per term, added (times a per-object gain) to each listed object's nominal position, so linked
//     objects move together (the two halves of a wall keep their gap) and a gain of -1 / +1 on
//     opposite halves widens the gap. Draws come from RngStream(seed, env, kPurposeTaskRandomise):
//     deterministic per seed and environment, independent of the thread count.
// Actions are the controller's: lee_position_control gets offsets from the current position
// (clipped to +-action_clip_m, zero = hold here, as position_setpoint_task), lee_velocity_control
// [vx, vy, vz, yaw_rate] clamped to [-1, 1] and scaled by max_speed_m_s / max_yaw_rate_rad_s.
//
// register_custom_task(spec) adds it to custom_tasks() and its TaskConfig to registries().tasks, so
// `kestrel run --task ID` and a scenario's `task: ID` both find it. The worked example,
// "goal_box_through_gap", is registered with the built-ins (goal_box_through_gap_spec()).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "kestrel/kernel/rng.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/task.hpp"

namespace kestrel::sim {

/// RNG purpose of the custom tasks' randomisation terms (above kPurposeUser, distinct from the
/// World's purposes).
constexpr std::uint32_t kPurposeTaskRandomise = static_cast<std::uint32_t>(kPurposeUser) + 1;

struct SceneObjectSpec {
  std::string name;
  bool solid = true;             // false: a region (no collision, not rendered)
  Vec3 position_w = Vec3::Zero();  // nominal centre (world frame)
  Vec3 half_extents_m = Vec3::Constant(0.5_r);  // a box
  int semantic_id = 20;
};

enum class ObsTermKind : std::uint8_t { position_error_to, orientation, linear_velocity_b, angular_velocity_b, previous_actions, image_pool };
struct ObservationTerm {
  ObsTermKind kind = ObsTermKind::orientation;
  std::string object;            // position_error_to
  int rows = 4, cols = 4;        // image_pool
};

enum class TerminationKind : std::uint8_t { inside_box, crash, timeout };
struct TerminationTerm {
  TerminationKind kind = TerminationKind::crash;
  std::string object;            // inside_box: a named object (its x / y ranges)
  real height_threshold_m = 1;   // inside_box: robot z - box bottom must be <= this
};

enum class RewardKind : std::uint8_t { progress_to, distance_to, success, crash, action_rate, alive };
struct RewardTerm {
  RewardKind kind = RewardKind::alive;
  std::string object;            // progress_to / distance_to
  float weight = 1;              // reward += weight * term
};

struct RandomizationTerm {
  std::string name;
  std::vector<std::string> objects;
  std::vector<Vec3> gains;       // per object (empty: all ones)
  Vec3 min_offset_m = Vec3::Zero(), max_offset_m = Vec3::Zero();
};

struct CustomTaskSpec;
/// A scripted policy for `kestrel run --policy scripted`: writes one environment's action from
/// the robot's position and the objects' current centres (index = position in spec.objects).
using CustomScriptedPolicy =
    std::function<void(const CustomTaskSpec& spec, const Vec3& robot_position_w, const Vec3* object_centres_w, float* action)>;

struct CustomTaskSpec {
  std::string id;
  std::string description;
  TaskDefaults defaults;         // scene: sim, env, robot, controller, sensors by registry name
  int episode_len_env_steps = 1000;
  Vec3 min_init_position_ratio = Vec3(0.1_r, 0.1_r, 0.1_r);  // robot start in the bounds
  Vec3 max_init_position_ratio = Vec3(0.2_r, 0.9_r, 0.9_r);
  std::vector<SceneObjectSpec> objects;
  std::vector<ObservationTerm> observations;
  std::vector<TerminationTerm> terminations;
  std::vector<RewardTerm> rewards;
  std::vector<RandomizationTerm> randomizations;
  float action_clip_m = 1.0f;                   // lee_position_control
  float max_speed_m_s = 2.0f, max_yaw_rate_rad_s = 1.0f;  // lee_velocity_control
  CustomScriptedPolicy scripted;                // optional
};

/// The custom-task registry (ids -> specs), with goal_box_through_gap registered.
Registry<CustomTaskSpec>& custom_tasks();
/// Checks the spec (names resolve, at least one term of each kind that needs one, sizes), then
/// registers it in custom_tasks() and its TaskConfig in registries().tasks. False + message if
/// the id is taken or the spec is bad (nothing registered then).
bool register_custom_task(const CustomTaskSpec& spec, std::string& error);
/// The TaskConfig a custom task's id maps to in registries().tasks.
TaskConfig custom_task_config(const CustomTaskSpec& spec);
/// Builds the custom task named by config.task.name with config's sim/env/robot/controller/sensors;
/// the spec's solid objects are added to the environment.
std::unique_ptr<Task> make_custom_task(const WorldConfig& config, std::string& error);
/// As above with an explicit spec (for specs not registered, e.g. in tests), on `backend`.
/// Rigid: lee_position_control, lee_velocity_control or lee_attitude_control; the objects are 3-D
/// boxes. Planar: the fixed-altitude multirotor with lee_position_control or lee_velocity_control;
/// solid objects become task-owned Box2D boxes (x / y extents); the terms see the objects at the
/// flight altitude (z errors 0, horizontal distances) and inside_box checks x / y only (the height
/// threshold does not apply at a fixed altitude); image_pool pools the 2-D lidar (default 128
/// beams) into one row of rows * cols sectors (the same observation size). The ground vehicle is
/// refused. In both, Simulator::set_obstacle_boxes moves the objects at every reset.
std::unique_ptr<Task> make_custom_task(const WorldConfig& config, const CustomTaskSpec& spec, Backend backend, std::string& error);
inline std::unique_ptr<Task> make_custom_task(const WorldConfig& config, const CustomTaskSpec& spec, std::string& error) {
  return make_custom_task(config, spec, Backend::rigid, error);
}

/// Extra access a custom task gives tests and tools (make_custom_task returns a Task whose
/// dynamic type implements it; custom_task_view() returns null for other tasks).
class CustomTaskView {
 public:
  virtual ~CustomTaskView();
  /// Current centre of a named object in an environment (after the last reset's randomisation).
  virtual Vec3 object_centre(int env, const std::string& name) const = 0;
  /// Evaluates the termination terms for env's current robot state: 1 success (inside the goal
  /// box), 2 crash, 3 timeout, 0 none (checked in the order the terms are listed).
  virtual int evaluate_terminations(int env) const = 0;
};
const CustomTaskView* custom_task_view(const Task& task);

/// Registers the tasks' built-ins into `r` (called by register_builtins): the TaskConfigs of
/// navigation_task and goal_box_through_gap, and the goal_box_through_gap scene env "goal_box_room".
void register_task_builtins(Registries& r);

/// The worked example: a wall across the room at x = 0 with a vertical gap (lateral position
/// uniform in +-1.2 m, width 0.9..1.2 m, both drawn at every reset), a goal box region on the
/// floor behind it (its centre drawn in y +-1.5 m); the robot starts in front of the wall and must
/// fly through the gap and settle into the box (x / y inside the box, at most 1 m above its floor).
CustomTaskSpec goal_box_through_gap_spec();

}  // namespace kestrel::sim
