// Custom tasks from terms (see custom_task.hpp): spec checking, registration, and the task that
// evaluates the terms over the batched World.
#include "kestrel/sim/custom_task.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "kestrel/kernel/quaternion.hpp"
#include "task_access.hpp"

namespace kestrel::sim {

CustomTaskView::~CustomTaskView() = default;

namespace {

constexpr int kCustomActionDim = 4;

int find_object(const CustomTaskSpec& s, const std::string& name) {
  for (std::size_t i = 0; i < s.objects.size(); ++i)
    if (s.objects[i].name == name) return static_cast<int>(i);
  return -1;
}

std::string object_names(const CustomTaskSpec& s) {
  std::string out;
  for (const SceneObjectSpec& o : s.objects) out += (out.empty() ? "" : ", ") + o.name;
  return out.empty() ? std::string("(none)") : out;
}

int obs_term_dim(const ObservationTerm& t) {
  switch (t.kind) {
    case ObsTermKind::position_error_to: return 3;
    case ObsTermKind::orientation: return 4;
    case ObsTermKind::linear_velocity_b: return 3;
    case ObsTermKind::angular_velocity_b: return 3;
    case ObsTermKind::previous_actions: return kCustomActionDim;
    case ObsTermKind::image_pool: return t.rows * t.cols;
  }
  return 0;
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

class CustomTask final : public Task, public CustomTaskView {
 public:
  CustomTask(std::unique_ptr<World> w, const CustomTaskSpec& spec, std::vector<int> slot_class, int sensor, int obs_dim)
      : Task(std::move(w), obs_dim, kCustomActionDim), spec_(spec), slot_class_(std::move(slot_class)), sensor_(sensor) {
    world_->set_auto_reset(false);
    const std::size_t n = static_cast<std::size_t>(num_envs_), no = spec_.objects.size();
    centres_.assign(n * no, Vec3::Zero());
    prev_dist_.assign(n * spec_.rewards.size(), 0.0f);
    action_.assign(n * kCustomActionDim, 0.0f);
    action_prev_.assign(n * kCustomActionDim, 0.0f);
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
    // Object names resolved once (check_spec has proven they exist): no string lookups per step.
    for (const ObservationTerm& t : spec_.observations) obs_obj_.push_back(find_object(spec_, t.object));
    for (const TerminationTerm& t : spec_.terminations) term_obj_.push_back(find_object(spec_, t.object));
    for (const RewardTerm& t : spec_.rewards) rew_obj_.push_back(find_object(spec_, t.object));
    for (const RandomizationTerm& r : spec_.randomizations) {
      std::vector<int> ids;
      for (const std::string& o : r.objects) ids.push_back(find_object(spec_, o));
      rand_obj_.push_back(ids);
    }
    reset();
  }

  const char* name() const override { return spec_.id.c_str(); }

  void step(const float* actions) override {
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      const float* in = actions + i * kCustomActionDim;
      float* cur = &action_[i * kCustomActionDim];
      float* prev = &action_prev_[i * kCustomActionDim];
      const bool position = kind_ == ControllerKind::lee_position;
      const float lim = position ? spec_.action_clip_m : 1.0f;
      real a[kCustomActionDim];
      for (int k = 0; k < kCustomActionDim; ++k) {
        prev[k] = cur[k];
        const float x = in[k];
        // Clip; NaN becomes 0 and never reaches the controller. Yaw (lee_position) is absolute.
        const float l = (position && k == 3) ? 10.0f : lim;
        cur[k] = x >= -l && x <= l ? x : (x > l ? l : (x < -l ? -l : 0.0f));
      }
      if (position) {
        const Vec3& p = task_access::robot(*world_, env).position_w;
        for (int k = 0; k < 3; ++k) a[k] = p[k] + static_cast<real>(cur[k]);
        a[3] = static_cast<real>(cur[3]);
      } else if (kind_ == ControllerKind::lee_velocity) {
        for (int k = 0; k < 3; ++k) a[k] = static_cast<real>(cur[k] * spec_.max_speed_m_s);
        a[3] = static_cast<real>(cur[3] * spec_.max_yaw_rate_rad_s);
      } else {
        for (int k = 0; k < kCustomActionDim; ++k) a[k] = static_cast<real>(cur[k]);
      }
      task_access::set_action(*world_, env, a, kCustomActionDim);
    }
    world_->step(1);
    ++infos_.steps;
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      const int why = evaluate_terminations(env);
      const bool success = why == 1, crash = why == 2, timeout = why == 3;
      const Vec3 p = task_access::robot(*world_, env).position_w;
      float r = 0;
      for (std::size_t k = 0; k < spec_.rewards.size(); ++k) {
        const RewardTerm& t = spec_.rewards[k];
        float v = 0;
        switch (t.kind) {
          case RewardKind::progress_to: {
            const float d = distance_to(env, rew_obj_[k], p);
            float& prev_d = prev_dist_[i * spec_.rewards.size() + k];
            v = prev_d - d;
            prev_d = d;
            break;
          }
          case RewardKind::distance_to: v = distance_to(env, rew_obj_[k], p); break;
          case RewardKind::success: v = success ? 1.0f : 0.0f; break;
          case RewardKind::crash: v = crash ? 1.0f : 0.0f; break;
          case RewardKind::action_rate:
            for (int j = 0; j < kCustomActionDim; ++j) {
              const float da = action_[i * kCustomActionDim + j] - action_prev_[i * kCustomActionDim + j];
              v += da * da;
            }
            break;
          case RewardKind::alive: v = 1.0f; break;
        }
        r += t.weight * v;
      }
      rewards_[i] = r;
      terminations_[i] = (success || crash) ? 1 : 0;
      truncations_[i] = timeout ? 1 : 0;
      episode_reward_[i] += static_cast<double>(r);
      if (why != 0) {
        ++infos_.episodes;
        infos_.episode_reward_sum += episode_reward_[i];
        if (timeout) {
          ++infos_.truncations;
        } else {
          ++infos_.terminations;
          if (success) ++infos_.successes;
          else ++infos_.crashes;
        }
        reset_env_and_objects(env);  // auto-reset: the row below is the new episode's first observation
      }
      write_obs(env);
    }
  }

  bool scripted_actions(float* actions) const override {
    if (!spec_.scripted) return false;
    const std::size_t no = spec_.objects.size();
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      spec_.scripted(spec_, task_access::robot(*world_, env).position_w, no ? &centres_[i * no] : nullptr,
                     actions + i * kCustomActionDim);
    }
    return true;
  }

  Vec3 object_centre(int env, const std::string& name) const override {
    const int k = find_object(spec_, name);
    if (k < 0 || env < 0 || env >= num_envs_) return Vec3::Constant(std::numeric_limits<real>::quiet_NaN());
    return centres_[static_cast<std::size_t>(env) * spec_.objects.size() + static_cast<std::size_t>(k)];
  }

  int evaluate_terminations(int env) const override {
    const Vec3 p = task_access::robot(*world_, env).position_w;
    for (std::size_t j = 0; j < spec_.terminations.size(); ++j) {
      const TerminationTerm& t = spec_.terminations[j];
      switch (t.kind) {
        case TerminationKind::inside_box: {
          const int k = term_obj_[j];
          const Vec3& c = centre(env, k);
          const Vec3& h = spec_.objects[static_cast<std::size_t>(k)].half_extents_m;
          const bool inside = p[0] >= c[0] - h[0] && p[0] <= c[0] + h[0] && p[1] >= c[1] - h[1] && p[1] <= c[1] + h[1] &&
                              p[2] - (c[2] - h[2]) <= t.height_threshold_m;
          if (inside) return 1;
          break;
        }
        case TerminationKind::crash:
          if (task_access::contact_crash(*world_, env) || task_access::out_of_bounds(*world_, env)) return 2;
          break;
        case TerminationKind::timeout:
          if (world_->episode_step(env) >= len_) return 3;
          break;
      }
    }
    return 0;
  }

 private:
  const Vec3& centre(int env, int object) const {
    return centres_[static_cast<std::size_t>(env) * spec_.objects.size() + static_cast<std::size_t>(object)];
  }
  float distance_to(int env, int object, const Vec3& p) const { return static_cast<float>((centre(env, object) - p).norm()); }

  // World reset (layout, start), then the randomisation terms move the named objects and the
  // solid ones are written into their obstacle slots.
  void reset_env_and_objects(int env) {
    world_->reset_env(env);
    const std::size_t i = static_cast<std::size_t>(env), no = spec_.objects.size();
    Vec3* c = no ? &centres_[i * no] : nullptr;
    for (std::size_t k = 0; k < no; ++k) c[k] = spec_.objects[k].position_w;
    RngStream& rng = rng_[i];
    for (std::size_t t = 0; t < spec_.randomizations.size(); ++t) {
      const RandomizationTerm& r = spec_.randomizations[t];
      Vec3 u;
      for (int a = 0; a < 3; ++a) u[a] = r.min_offset_m[a] < r.max_offset_m[a] ? rng.uniform(r.min_offset_m[a], r.max_offset_m[a]) : r.min_offset_m[a];
      for (std::size_t j = 0; j < r.objects.size(); ++j) c[rand_obj_[t][j]] += r.gains.empty() ? u : Vec3(r.gains[j].cwiseProduct(u));
    }
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
    const Vec3 p = task_access::robot(*world_, env).position_w;
    for (std::size_t k = 0; k < spec_.rewards.size(); ++k)
      if (spec_.rewards[k].kind == RewardKind::progress_to) prev_dist_[i * spec_.rewards.size() + k] = distance_to(env, rew_obj_[k], p);
    for (int a = 0; a < kCustomActionDim; ++a) action_[i * kCustomActionDim + a] = action_prev_[i * kCustomActionDim + a] = 0;
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

  void write_obs(int env) {
    const std::size_t i = static_cast<std::size_t>(env);
    float* o = &obs_[i * static_cast<std::size_t>(obs_dim_)];
    const task_access::RobotView r = task_access::robot(*world_, env);
    int at = 0;
    for (std::size_t j = 0; j < spec_.observations.size(); ++j) {
      const ObservationTerm& t = spec_.observations[j];
      switch (t.kind) {
        case ObsTermKind::position_error_to: {
          const Vec3 e = task_access::world_to_vehicle(r.orientation_wb, centre(env, obs_obj_[j]) - r.position_w);
          for (int k = 0; k < 3; ++k) o[at + k] = static_cast<float>(e[k]);
          break;
        }
        case ObsTermKind::orientation:
          for (int k = 0; k < 4; ++k) o[at + k] = static_cast<float>(r.orientation_wb.coeffs()[k]);  // xyzw
          break;
        case ObsTermKind::linear_velocity_b:
          for (int k = 0; k < 3; ++k) o[at + k] = static_cast<float>(r.linvel_b[k]);
          break;
        case ObsTermKind::angular_velocity_b:
          for (int k = 0; k < 3; ++k) o[at + k] = static_cast<float>(r.angvel_b[k]);
          break;
        case ObsTermKind::previous_actions:
          for (int k = 0; k < kCustomActionDim; ++k) o[at + k] = action_[i * kCustomActionDim + k];
          break;
        case ObsTermKind::image_pool:
          min_pool_ranges(world_->sensor_ranges(env, sensor_), world_->sensor_height(sensor_), world_->sensor_width(sensor_),
                          max_range_m_, t.rows, t.cols, o + at);
          break;
      }
      at += obs_term_dim(t);
    }
  }

  CustomTaskSpec spec_;
  std::vector<int> slot_class_;  // per object: its asset class index (solid), -1 (region)
  std::vector<int> obs_obj_, term_obj_, rew_obj_;  // per term: object index (-1: none)
  std::vector<std::vector<int>> rand_obj_;          // per randomisation term: object indices
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
  if (!check_spec(spec, error)) return false;
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
  if (!check_spec(spec, error)) return nullptr;
  const std::string where = "custom task '" + spec.id + "': ";
  if (config.robot.robots_per_env != 1) {
    error = where + "needs robots_per_env = 1";
    return nullptr;
  }
  const ControllerKind k = config.controller.kind;
  if (k != ControllerKind::lee_position && k != ControllerKind::lee_velocity && k != ControllerKind::lee_attitude) {
    error = where + "controller " + config.controller.name +
            " is not supported; expected lee_position_control, lee_velocity_control or lee_attitude_control";
    return nullptr;
  }
  WorldConfig wc = config;
  wc.task.kind = TaskKind::hover;
  wc.robot.min_init_position_ratio = spec.min_init_position_ratio;
  wc.robot.max_init_position_ratio = spec.max_init_position_ratio;
  // Solid objects: one asset class each (one slot, kept at every curriculum level, parked as a
  // tiny cube in the corner until the task's reset writes its box), found again by class index.
  std::vector<int> slot_class(spec.objects.size(), -1);
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
      return nullptr;
    }
    slot_class[i] = static_cast<int>(wc.env.assets.size());
    wc.env.assets.push_back(c);
  }
  int sensor = -1, obs_dim = 0;
  for (std::size_t s = 0; s < wc.robot.sensors.size() && sensor < 0; ++s)
    if (wc.robot.sensors[s].kind != SensorKind::imu) sensor = static_cast<int>(s);
  for (const ObservationTerm& t : spec.observations) {
    if (t.kind == ObsTermKind::image_pool && sensor < 0) {
      error = where + "the image_pool observation needs a ray sensor (lidar, ToF or camera) on the robot, e.g. `sensors: [vl53l5cx]`";
      return nullptr;
    }
    obs_dim += obs_term_dim(t);
  }
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
