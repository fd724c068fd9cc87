// Custom tasks from terms (see custom_task.hpp): spec checking, registration, and the task that
// evaluates the terms over the batched World.
#include "kestrel/sim/custom_task.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "kestrel/kernel/quaternion.hpp"
#include "custom_task_terms.hpp"
#include "task_access.hpp"

namespace kestrel::sim {

CustomTaskView::~CustomTaskView() = default;

namespace custom_terms {

int find_object(const CustomTaskSpec& s, const std::string& name) {
  for (std::size_t i = 0; i < s.objects.size(); ++i)
    if (s.objects[i].name == name) return static_cast<int>(i);
  return -1;
}

Vec3 object_centre(const CustomTaskSpec& s, const std::vector<Vec3>& centres, int num_envs, int env, const std::string& name) {
  const int k = find_object(s, name);
  if (k < 0 || env < 0 || env >= num_envs) return Vec3::Constant(std::numeric_limits<real>::quiet_NaN());
  return centres[static_cast<std::size_t>(env) * s.objects.size() + static_cast<std::size_t>(k)];
}

std::string object_names(const CustomTaskSpec& s) {
  std::string out;
  for (const SceneObjectSpec& o : s.objects) out += (out.empty() ? "" : ", ") + o.name;
  return out.empty() ? std::string("(none)") : out;
}

namespace {
int obs_term_dim(const ObservationTerm& t) {
  switch (t.kind) {
    case ObsTermKind::position_error_to: return 3;
    case ObsTermKind::orientation: return 4;
    case ObsTermKind::linear_velocity_b: return 3;
    case ObsTermKind::angular_velocity_b: return 3;
    case ObsTermKind::previous_actions: return kActionDim;
    case ObsTermKind::image_pool: return t.rows * t.cols;
  }
  return 0;
}
}  // namespace

int obs_dim(const CustomTaskSpec& s) {
  int n = 0;
  for (const ObservationTerm& t : s.observations) n += obs_term_dim(t);
  return n;
}

// Spec checks that do not need a world: every named object exists, sizes are sane.
bool check_spec(const CustomTaskSpec& s, std::string& error) {
  const std::string where = "custom task '" + s.id + "': ";
  if (s.id.empty()) {
    error = "custom task: empty id";
    return false;
  }
  if (s.episode_len_env_steps < 1) {
    error = where + "episode_len_env_steps: expected a positive integer";
    return false;
  }
  for (std::size_t i = 0; i < s.objects.size(); ++i) {
    const SceneObjectSpec& o = s.objects[i];
    if (o.name.empty() || find_object(s, o.name) != static_cast<int>(i)) {
      error = where + "objects[" + std::to_string(i) + "]: names must be non-empty and unique";
      return false;
    }
    if (!(o.half_extents_m.minCoeff() > 0) || !o.position_w.allFinite()) {
      error = where + "object " + o.name + ": expected positive half extents and a finite position";
      return false;
    }
  }
  auto known = [&](const std::string& name, const std::string& field) {
    if (find_object(s, name) >= 0) return true;
    error = where + field + ": unknown object '" + name + "'; objects: " + object_names(s);
    return false;
  };
  if (s.observations.empty()) {
    error = where + "needs at least one observation term";
    return false;
  }
  for (std::size_t i = 0; i < s.observations.size(); ++i) {
    const ObservationTerm& t = s.observations[i];
    if (t.kind == ObsTermKind::position_error_to && !known(t.object, "observations[" + std::to_string(i) + "]")) return false;
    if (t.kind == ObsTermKind::image_pool && (t.rows < 1 || t.cols < 1)) {
      error = where + "observations[" + std::to_string(i) + "]: image_pool rows and cols must be >= 1";
      return false;
    }
  }
  bool has_timeout = false;
  for (std::size_t i = 0; i < s.terminations.size(); ++i) {
    const TerminationTerm& t = s.terminations[i];
    if (t.kind == TerminationKind::inside_box && !known(t.object, "terminations[" + std::to_string(i) + "]")) return false;
    has_timeout = has_timeout || t.kind == TerminationKind::timeout;
  }
  if (!has_timeout) {
    error = where + "needs a timeout termination term (episodes must end)";
    return false;
  }
  for (std::size_t i = 0; i < s.rewards.size(); ++i) {
    const RewardTerm& t = s.rewards[i];
    if ((t.kind == RewardKind::progress_to || t.kind == RewardKind::distance_to) && !known(t.object, "rewards[" + std::to_string(i) + "]"))
      return false;
    if (!std::isfinite(t.weight)) {
      error = where + "rewards[" + std::to_string(i) + "]: weight must be finite";
      return false;
    }
  }
  for (const RandomizationTerm& r : s.randomizations) {
    for (const std::string& o : r.objects)
      if (!known(o, "randomizations." + r.name)) return false;
    if (!r.gains.empty() && r.gains.size() != r.objects.size()) {
      error = where + "randomizations." + r.name + ": gains must be empty or one per object";
      return false;
    }
    if (!(r.min_offset_m.array() <= r.max_offset_m.array()).all()) {
      error = where + "randomizations." + r.name + ": expected min_offset_m <= max_offset_m per axis";
      return false;
    }
  }
  return true;
}

Resolved::Resolved(const CustomTaskSpec& s) {
  for (const ObservationTerm& t : s.observations) obs_obj.push_back(find_object(s, t.object));
  for (const TerminationTerm& t : s.terminations) term_obj.push_back(find_object(s, t.object));
  for (const RewardTerm& t : s.rewards) rew_obj.push_back(find_object(s, t.object));
  for (const RandomizationTerm& r : s.randomizations) {
    std::vector<int> ids;
    for (const std::string& o : r.objects) ids.push_back(find_object(s, o));
    rand_obj.push_back(ids);
  }
}

bool prepare_config(const WorldConfig& config, const CustomTaskSpec& spec, const std::vector<ControllerKind>& controllers,
                    const std::string& controller_names, const std::string& where, WorldConfig& wc, std::vector<int>& slot_class,
                    std::string& error) {
  if (config.robot.robots_per_env != 1) {
    error = where + "needs robots_per_env = 1";
    return false;
  }
  if (std::find(controllers.begin(), controllers.end(), config.controller.kind) == controllers.end()) {
    error = where + "controller " + config.controller.name + " is not supported; expected " + controller_names;
    return false;
  }
  wc = config;
  wc.task.kind = TaskKind::hover;
  wc.robot.min_init_position_ratio = spec.min_init_position_ratio;
  wc.robot.max_init_position_ratio = spec.max_init_position_ratio;
  // Solid objects: one asset class each (one slot, kept at every curriculum level, parked as a
  // tiny cube in the corner until the task's reset writes its box), found again by class index.
  slot_class.assign(spec.objects.size(), -1);
  for (std::size_t i = 0; i < spec.objects.size(); ++i) {
    if (!spec.objects[i].solid) continue;
    AssetClass c;
    c.name = spec.id + "." + spec.objects[i].name;
    c.kind = AssetKind::cube;
    c.num_assets = c.min_num_assets = 1;
    c.keep_in_env = true;
    c.min_position_ratio = c.max_position_ratio = Vec3::Zero();
    c.min_size_m = c.max_size_m = Vec3::Constant(0.01_r);
    c.semantic_id = spec.objects[i].semantic_id;
    if (wc.env.assets.size() >= 255) {
      error = where + "too many asset classes in the environment (at most 255)";
      return false;
    }
    slot_class[i] = static_cast<int>(wc.env.assets.size());
    wc.env.assets.push_back(c);
  }
  return true;
}

void randomize_objects(const CustomTaskSpec& s, const Resolved& res, RngStream& rng, Vec3* c) {
  for (std::size_t k = 0; k < s.objects.size(); ++k) c[k] = s.objects[k].position_w;
  for (std::size_t t = 0; t < s.randomizations.size(); ++t) {
    const RandomizationTerm& r = s.randomizations[t];
    Vec3 u;
    for (int a = 0; a < 3; ++a) u[a] = r.min_offset_m[a] < r.max_offset_m[a] ? rng.uniform(r.min_offset_m[a], r.max_offset_m[a]) : r.min_offset_m[a];
    for (std::size_t j = 0; j < r.objects.size(); ++j) c[res.rand_obj[t][j]] += r.gains.empty() ? u : Vec3(r.gains[j].cwiseProduct(u));
  }
}

void clip_action(const CustomTaskSpec& s, ControllerKind kind, const float* in, float* out) {
  const bool position = kind == ControllerKind::lee_position;
  const float lim = position ? s.action_clip_m : 1.0f;
  for (int k = 0; k < kActionDim; ++k) {
    const float x = in[k];
    // Clip; NaN becomes 0 and never reaches the controller. Yaw (lee_position) is absolute.
    const float l = (position && k == 3) ? 10.0f : lim;
    out[k] = x >= -l && x <= l ? x : (x > l ? l : (x < -l ? -l : 0.0f));
  }
}

bool inside_box(const CustomTaskSpec& s, const TerminationTerm& t, int object, const Vec3& c, const Vec3& p, bool check_height) {
  const Vec3& h = s.objects[static_cast<std::size_t>(object)].half_extents_m;
  const bool xy = p[0] >= c[0] - h[0] && p[0] <= c[0] + h[0] && p[1] >= c[1] - h[1] && p[1] <= c[1] + h[1];
  return xy && (!check_height || p[2] - (c[2] - h[2]) <= t.height_threshold_m);
}

int evaluate_terminations(const CustomTaskSpec& s, const Resolved& r, const Vec3* centres, const Vec3& p, bool check_height,
                          bool crash, bool timeout) {
  for (std::size_t j = 0; j < s.terminations.size(); ++j) {
    const TerminationTerm& t = s.terminations[j];
    switch (t.kind) {
      case TerminationKind::inside_box:
        if (inside_box(s, t, r.term_obj[j], centres[r.term_obj[j]], p, check_height)) return 1;
        break;
      case TerminationKind::crash:
        if (crash) return 2;
        break;
      case TerminationKind::timeout:
        if (timeout) return 3;
        break;
    }
  }
  return 0;
}

namespace {
float distance(const Vec3* centres, int object, const Vec3& p) { return static_cast<float>((centres[object] - p).norm()); }
}  // namespace

float reward(const CustomTaskSpec& s, const Resolved& res, const Vec3* centres, const Vec3& p, bool success, bool crash,
             const float* action, const float* action_prev, float* prev_dist) {
  float r = 0;
  for (std::size_t k = 0; k < s.rewards.size(); ++k) {
    const RewardTerm& t = s.rewards[k];
    float v = 0;
    switch (t.kind) {
      case RewardKind::progress_to: {
        const float d = distance(centres, res.rew_obj[k], p);
        v = prev_dist[k] - d;
        prev_dist[k] = d;
        break;
      }
      case RewardKind::distance_to: v = distance(centres, res.rew_obj[k], p); break;
      case RewardKind::success: v = success ? 1.0f : 0.0f; break;
      case RewardKind::crash: v = crash ? 1.0f : 0.0f; break;
      case RewardKind::action_rate:
        for (int j = 0; j < kActionDim; ++j) {
          const float da = action[j] - action_prev[j];
          v += da * da;
        }
        break;
      case RewardKind::alive: v = 1.0f; break;
    }
    r += t.weight * v;
  }
  return r;
}

void reset_progress(const CustomTaskSpec& s, const Resolved& res, const Vec3* centres, const Vec3& p, float* prev_dist) {
  for (std::size_t k = 0; k < s.rewards.size(); ++k)
    if (s.rewards[k].kind == RewardKind::progress_to) prev_dist[k] = distance(centres, res.rew_obj[k], p);
}

void count_episode(int why, double episode_reward, TaskInfos& infos) {
  ++infos.episodes;
  infos.episode_reward_sum += episode_reward;
  if (why == 3) {
    ++infos.truncations;
  } else {
    ++infos.terminations;
    if (why == 1) ++infos.successes;
    else ++infos.crashes;
  }
}

void write_obs(const CustomTaskSpec& s, const Resolved& res, const Vec3* centres, const ObsInput& in, float* o) {
  int at = 0;
  for (std::size_t j = 0; j < s.observations.size(); ++j) {
    const ObservationTerm& t = s.observations[j];
    switch (t.kind) {
      case ObsTermKind::position_error_to: {
        const Vec3 e = task_access::world_to_vehicle(in.orientation_wb, centres[res.obs_obj[j]] - in.position_w);
        for (int k = 0; k < 3; ++k) o[at + k] = static_cast<float>(e[k]);
        break;
      }
      case ObsTermKind::orientation:
        for (int k = 0; k < 4; ++k) o[at + k] = static_cast<float>(in.orientation_wb.coeffs()[k]);  // xyzw
        break;
      case ObsTermKind::linear_velocity_b:
        for (int k = 0; k < 3; ++k) o[at + k] = static_cast<float>(in.linvel_b[k]);
        break;
      case ObsTermKind::angular_velocity_b:
        for (int k = 0; k < 3; ++k) o[at + k] = static_cast<float>(in.angvel_b[k]);
        break;
      case ObsTermKind::previous_actions:
        for (int k = 0; k < kActionDim; ++k) o[at + k] = in.action[k];
        break;
      case ObsTermKind::image_pool:
        if (in.height == 1) min_pool_ranges(in.ranges, 1, in.width, in.max_range_m, 1, t.rows * t.cols, o + at);
        else min_pool_ranges(in.ranges, in.height, in.width, in.max_range_m, t.rows, t.cols, o + at);
        break;
    }
    at += obs_term_dim(t);
  }
}

}  // namespace custom_terms

namespace {

using custom_terms::kActionDim;

class CustomTask final : public Task, public CustomTaskView {
 public:
  CustomTask(std::unique_ptr<World> w, const CustomTaskSpec& spec, std::vector<int> slot_class, int sensor, int obs_dim)
      : Task(std::move(w), obs_dim, kActionDim), spec_(spec), res_(spec_), slot_class_(std::move(slot_class)), sensor_(sensor) {
    world_->set_auto_reset(false);
    const std::size_t n = static_cast<std::size_t>(num_envs_), no = spec_.objects.size();
    centres_.assign(n * no, Vec3::Zero());
    prev_dist_.assign(n * spec_.rewards.size(), 0.0f);
    action_.assign(n * kActionDim, 0.0f);
    action_prev_.assign(n * kActionDim, 0.0f);
    episode_reward_.assign(n, 0.0);
    rng_.resize(n);
    for (std::size_t e = 0; e < n; ++e) rng_[e] = RngStream(world_->config().seed, static_cast<std::uint32_t>(e), kPurposeTaskRandomise);
    if (sensor_ >= 0) {
      const SensorConfig& sc = world_->sensor_config(sensor_);
      const sensors::RangeOutputParams& rp = sc.kind == SensorKind::camera ? sc.camera.range : sc.lidar.range;
      max_range_m_ = rp.normalize_range ? 1 : rp.max_range;
    }
    kind_ = world_->config().controller.kind;
    len_ = world_->config().task.episode_len_env_steps;
    reset();
  }

  const char* name() const override { return spec_.id.c_str(); }

  void step(const float* actions) override {
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      float* cur = &action_[i * kActionDim];
      float* prev = &action_prev_[i * kActionDim];
      for (int k = 0; k < kActionDim; ++k) prev[k] = cur[k];
      custom_terms::clip_action(spec_, kind_, actions + i * kActionDim, cur);
      real a[kActionDim];
      if (kind_ == ControllerKind::lee_position) {
        const Vec3& p = task_access::robot(*world_, env).position_w;
        for (int k = 0; k < 3; ++k) a[k] = p[k] + static_cast<real>(cur[k]);
        a[3] = static_cast<real>(cur[3]);
      } else if (kind_ == ControllerKind::lee_velocity) {
        for (int k = 0; k < 3; ++k) a[k] = static_cast<real>(cur[k] * spec_.max_speed_m_s);
        a[3] = static_cast<real>(cur[3] * spec_.max_yaw_rate_rad_s);
      } else {
        for (int k = 0; k < kActionDim; ++k) a[k] = static_cast<real>(cur[k]);
      }
      task_access::set_action(*world_, env, a, kActionDim);
    }
    world_->step(1);
    ++infos_.steps;
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      const int why = evaluate_terminations(env);
      const bool success = why == 1, crash = why == 2, timeout = why == 3;
      const Vec3 p = task_access::robot(*world_, env).position_w;
      const float r = custom_terms::reward(spec_, res_, env_centres(env), p, success, crash, &action_[i * kActionDim],
                                           &action_prev_[i * kActionDim], &prev_dist_[i * spec_.rewards.size()]);
      rewards_[i] = r;
      terminations_[i] = (success || crash) ? 1 : 0;
      truncations_[i] = timeout ? 1 : 0;
      episode_reward_[i] += static_cast<double>(r);
      if (why != 0) {
        custom_terms::count_episode(why, episode_reward_[i], infos_);
        keep_final_obs(env);
        reset_env_and_objects(env);  // auto-reset: the row below is the new episode's first observation
      }
      write_obs(env);
    }
  }

  bool scripted_actions(float* actions) const override {
    if (!spec_.scripted) return false;
    for (int env = 0; env < num_envs_; ++env)
      spec_.scripted(spec_, task_access::robot(*world_, env).position_w, env_centres(env),
                     actions + static_cast<std::size_t>(env) * kActionDim);
    return true;
  }

  Vec3 object_centre(int env, const std::string& name) const override {
    return custom_terms::object_centre(spec_, centres_, num_envs_, env, name);
  }

  int evaluate_terminations(int env) const override {
    const bool crash = task_access::contact_crash(*world_, env) || task_access::out_of_bounds(*world_, env);
    const bool timeout = world_->episode_step(env) >= len_;
    return custom_terms::evaluate_terminations(spec_, res_, env_centres(env), task_access::robot(*world_, env).position_w, true,
                                               crash, timeout);
  }

 private:
  const Vec3* env_centres(int env) const {
    return spec_.objects.empty() ? nullptr : &centres_[static_cast<std::size_t>(env) * spec_.objects.size()];
  }

  // World reset (layout, start), then the randomisation terms move the named objects and the
  // solid ones are written into their obstacle slots.
  void reset_env_and_objects(int env) {
    world_->reset_env(env);
    const std::size_t i = static_cast<std::size_t>(env), no = spec_.objects.size();
    Vec3* c = no ? &centres_[i * no] : nullptr;
    custom_terms::randomize_objects(spec_, res_, rng_[i], c);
    bool any = false;
    for (int s = 0; s < world_->num_obstacles(env); ++s) {
      Obstacle& o = world_->obstacle(env, s);
      for (std::size_t k = 0; k < no; ++k) {
        if (slot_class_[k] < 0 || o.class_index != slot_class_[k]) continue;
        o.shape = Shape();
        o.shape.type = ShapeType::box;
        o.shape.half_extents_m = spec_.objects[k].half_extents_m;
        o.shape.position_w = c[k];
        any = true;
      }
    }
    if (any) world_->obstacles_changed(env);  // sweep order and sensor images see the moved objects
    custom_terms::reset_progress(spec_, res_, c, task_access::robot(*world_, env).position_w, &prev_dist_[i * spec_.rewards.size()]);
    for (int a = 0; a < kActionDim; ++a) action_[i * kActionDim + a] = action_prev_[i * kActionDim + a] = 0;
    episode_reward_[i] = 0;
  }

  void reset_one(int env) override {
    reset_env_and_objects(env);
    const std::size_t i = static_cast<std::size_t>(env);
    rewards_[i] = 0;
    terminations_[i] = 0;
    truncations_[i] = 0;
    write_obs(env);
  }

  void write_obs(int env) override {
    const std::size_t i = static_cast<std::size_t>(env);
    const task_access::RobotView r = task_access::robot(*world_, env);
    custom_terms::ObsInput in;
    in.position_w = r.position_w;
    in.orientation_wb = r.orientation_wb;
    in.linvel_b = r.linvel_b;
    in.angvel_b = r.angvel_b;
    in.action = &action_[i * kActionDim];
    if (sensor_ >= 0) {
      in.ranges = world_->sensor_ranges(env, sensor_);
      in.height = world_->sensor_height(sensor_);
      in.width = world_->sensor_width(sensor_);
    }
    in.max_range_m = max_range_m_;
    custom_terms::write_obs(spec_, res_, env_centres(env), in, &obs_[i * static_cast<std::size_t>(obs_dim_)]);
  }

  CustomTaskSpec spec_;
  custom_terms::Resolved res_;
  std::vector<int> slot_class_;  // per object: its asset class index (solid), -1 (region)
  int sensor_ = -1;
  real max_range_m_ = 1;
  ControllerKind kind_ = ControllerKind::lee_position;
  int len_ = 0;
  std::vector<Vec3> centres_;        // envs x objects
  std::vector<float> prev_dist_;     // envs x reward terms (progress_to)
  std::vector<float> action_, action_prev_;
  std::vector<double> episode_reward_;
  std::vector<RngStream> rng_;
};

}  // namespace

TaskConfig custom_task_config(const CustomTaskSpec& spec) {
  TaskConfig t;
  t.name = spec.id;
  t.kind = TaskKind::hover;  // the World draws only the start; the terms define the goal
  t.episode_len_env_steps = spec.episode_len_env_steps;
  t.clearance_m = 0.1_r;
  t.line_of_sight = false;
  t.success_radius_m = 0;
  return t;
}

Registry<CustomTaskSpec>& custom_tasks() {
  static Registry<CustomTaskSpec> r = [] {
    Registry<CustomTaskSpec> x;
    const CustomTaskSpec g = goal_box_through_gap_spec();
    x.add(g.id, g.description, [] { return goal_box_through_gap_spec(); });
    return x;
  }();
  return r;
}

bool register_custom_task(const CustomTaskSpec& spec, std::string& error) {
  if (!custom_terms::check_spec(spec, error)) return false;
  if (custom_tasks().has(spec.id) || registries().tasks.has(spec.id) || spec.id == "navigation_task" ||
      spec.id == "position_setpoint_task") {
    error = "custom task '" + spec.id + "': the id is taken; registered task ids: " + rl_task_ids_joined();
    return false;
  }
  const CustomTaskSpec copy = spec;
  custom_tasks().add(spec.id, spec.description, [copy] { return copy; });
  registries().tasks.add(spec.id, spec.description, [copy] { return custom_task_config(copy); });
  return true;
}

std::unique_ptr<Task> make_custom_task(const WorldConfig& config, std::string& error) {
  CustomTaskSpec spec;
  if (!custom_tasks().make(config.task.name, spec)) {
    error = "unknown task '" + config.task.name + "'; registered task ids: " + rl_task_ids_joined();
    return nullptr;
  }
  return make_custom_task(config, spec, error);
}

std::unique_ptr<Task> make_custom_task(const WorldConfig& config, const CustomTaskSpec& spec, std::string& error) {
  if (!custom_terms::check_spec(spec, error)) return nullptr;
  const std::string where = "custom task '" + spec.id + "': ";
  WorldConfig wc;
  std::vector<int> slot_class;
  if (!custom_terms::prepare_config(config, spec, {ControllerKind::lee_position, ControllerKind::lee_velocity, ControllerKind::lee_attitude},
                                    "lee_position_control, lee_velocity_control or lee_attitude_control", where, wc, slot_class, error))
    return nullptr;
  int sensor = -1, obs_dim = 0;
  for (std::size_t s = 0; s < wc.robot.sensors.size() && sensor < 0; ++s)
    if (wc.robot.sensors[s].kind != SensorKind::imu) sensor = static_cast<int>(s);
  for (const ObservationTerm& t : spec.observations) {
    if (t.kind == ObsTermKind::image_pool && sensor < 0) {
      error = where + "the image_pool observation needs a ray sensor (lidar, ToF or camera) on the robot, e.g. `sensors: [vl53l5cx]`";
      return nullptr;
    }
  }
  obs_dim = custom_terms::obs_dim(spec);
  std::unique_ptr<World> w = World::create(wc, error);
  if (!w) return nullptr;
  for (const ObservationTerm& t : spec.observations)
    if (t.kind == ObsTermKind::image_pool && (w->sensor_height(sensor) < t.rows || w->sensor_width(sensor) < t.cols)) {
      error = where + "image_pool grid " + std::to_string(t.rows) + " x " + std::to_string(t.cols) + " is larger than the sensor image";
      return nullptr;
    }
  return std::unique_ptr<Task>(new CustomTask(std::move(w), spec, std::move(slot_class), sensor, obs_dim));
}

const CustomTaskView* custom_task_view(const Task& task) { return dynamic_cast<const CustomTaskView*>(&task); }

}  // namespace kestrel::sim
