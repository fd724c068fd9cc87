// The custom tasks' term evaluation (custom_task.cpp: one task class over the Simulator for every
// backend): one formula per term.
#pragma once

#include <string>
#include <vector>

#include "kestrel/sim/custom_task.hpp"

namespace kestrel::sim::custom_terms {

constexpr int kActionDim = 4;

int find_object(const CustomTaskSpec& s, const std::string& name);
/// Centre of the named object in environment `env` from the per-env table `centres` (num_envs x
/// objects); NaN for an unknown name or environment (what Task::object_centre promises).
Vec3 object_centre(const CustomTaskSpec& s, const std::vector<Vec3>& centres, int num_envs, int env, const std::string& name);
int obs_dim(const CustomTaskSpec& s);
/// Spec checks that do not need a world (names resolve, sizes, ranges).
bool check_spec(const CustomTaskSpec& s, std::string& error);

/// Object names resolved once per task (no string lookups per step).
struct Resolved {
  std::vector<int> obs_obj, term_obj, rew_obj;  // per term: object index (-1: none)
  std::vector<std::vector<int>> rand_obj;       // per randomisation term: object indices
  explicit Resolved(const CustomTaskSpec& s);
};

/// Checks robots_per_env and the controller (allowed: the list given, named in the message),
/// applies the spec's start ratios and a hover task kind, and adds one asset class per solid
/// object (a one-slot cube kept at every curriculum level; slot_class[k] = its class index, -1 for
/// regions). `where` prefixes the messages.
bool prepare_config(const WorldConfig& config, const CustomTaskSpec& spec, const std::vector<ControllerKind>& controllers,
                    const std::string& controller_names, const std::string& where, WorldConfig& wc, std::vector<int>& slot_class,
                    std::string& error);

/// Nominal centres, then every randomisation term's uniform draw (one per axis with a range, from
/// `rng`, in term order) times each object's gain.
void randomize_objects(const CustomTaskSpec& s, const Resolved& r, RngStream& rng, Vec3* centres);
/// Clips an action: +-action_clip_m (lee_position; its yaw, index 3, absolute within +-10 rad) or
/// +-1; NaN becomes 0.
void clip_action(const CustomTaskSpec& s, ControllerKind kind, const float* in, float* out);
/// Robot at p inside the box object (x / y ranges; with check_height also p_z - box bottom <= the
/// term's height threshold).
bool inside_box(const CustomTaskSpec& s, const TerminationTerm& t, int object, const Vec3& centre, const Vec3& p, bool check_height);
/// The termination terms in their order: 1 success (inside_box), 2 crash, 3 timeout, 0 none.
int evaluate_terminations(const CustomTaskSpec& s, const Resolved& r, const Vec3* centres, const Vec3& p, bool check_height,
                          bool crash, bool timeout);
/// Sum of weight * term; progress_to updates prev_dist (one per reward term).
float reward(const CustomTaskSpec& s, const Resolved& r, const Vec3* centres, const Vec3& p, bool success, bool crash,
             const float* action, const float* action_prev, float* prev_dist);
/// progress_to distances from the episode's start.
void reset_progress(const CustomTaskSpec& s, const Resolved& r, const Vec3* centres, const Vec3& p, float* prev_dist);
/// Episode counters of an ended episode (why: 1 success, 2 crash, 3 timeout).
void count_episode(int why, double episode_reward, TaskInfos& infos);

struct ObsInput {
  Vec3 position_w;
  Quat orientation_wb;
  Vec3 linvel_b, angvel_b;
  const float* action = nullptr;
  RangeImage image;  // image_pool: the robot's range image 0 (ranges null: none)
};
/// Writes the observation terms in order. image_pool pools the range image into rows x cols
/// cells, or into one row of rows * cols cells when the image is a single row (the planar lidar).
void write_obs(const CustomTaskSpec& s, const Resolved& r, const Vec3* centres, const ObsInput& in, float* out);

}  // namespace kestrel::sim::custom_terms
