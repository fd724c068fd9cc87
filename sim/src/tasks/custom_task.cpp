// Custom tasks from terms (see custom_task.hpp): spec checking, registration, and the task that
// evaluates the terms over the batched World.
#include "kestrel/sim/custom_task.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "kestrel/kernel/quaternion.hpp"
#include "custom_task_terms.hpp"
#include "task_support.hpp"

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
        const Vec3 e = task_support::world_to_vehicle(in.orientation_wb, centres[res.obs_obj[j]] - in.position_w);
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
        task_support::pool_image(in.image, t.rows, t.cols, o + at);
        break;
    }
    at += obs_term_dim(t);
  }
}

}  // namespace custom_terms

namespace {

using custom_terms::kActionDim;

// One class for every backend. Where the backend holds the altitude (planar multirotor) the
// terms see the objects at the flight altitude (their z replaced by it: position errors have z
// 0, distances are horizontal), inside_box checks x / y only (the robot cannot descend into the
// box), the vertical command is dropped, and the bounds rule reads x and y; object_centre()
// reports the drawn 3-D centres either way.
class CustomTask final : public Task, public CustomTaskView {
 public:
  CustomTask(std::unique_ptr<Simulator> s, const CustomTaskSpec& spec, std::vector<int> slot_class)
      : Task(std::move(s), custom_terms::obs_dim(spec), kActionDim), spec_(spec), res_(spec_), slot_class_(std::move(slot_class)) {
    const std::size_t n = static_cast<std::size_t>(num_envs_), no = spec_.objects.size();
    centres_.assign(n * no, Vec3::Zero());
    seen_.assign(n * no, Vec3::Zero());
    prev_dist_.assign(n * spec_.rewards.size(), 0.0f);
    action_.assign(n * kActionDim, 0.0f);
    action_prev_.assign(n * kActionDim, 0.0f);
    boxes_.reserve(no);
    rng_.resize(n);
    for (std::size_t e = 0; e < n; ++e) rng_[e] = RngStream(sim_->config().seed, sim_->config().env.global_env(static_cast<int>(e)), kPurposeTaskRandomise);
    kind_ = sim_->config().controller.kind;
    flat_ = sim_->holds_altitude();
    reset();
  }

  const char* name() const override { return spec_.id.c_str(); }

  void step(const float* actions) override {
    const int ad = sim_->action_dim();
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      float* cur = &action_[i * kActionDim];
      float* prev = &action_prev_[i * kActionDim];
      for (int k = 0; k < kActionDim; ++k) prev[k] = cur[k];
      custom_terms::clip_action(spec_, kind_, actions + i * kActionDim, cur);
      if (flat_) cur[2] = 0.0f;  // the altitude is held: no vertical command (nor its action-rate penalty)
      real* a = &sim_actions_[i * static_cast<std::size_t>(ad)];
      if (kind_ == ControllerKind::lee_position) {  // offsets from the current position
        const Vec3 p = position(env);
        for (int k = 0; k < 3; ++k) a[k] = p[k] + static_cast<real>(cur[k]);
        a[3] = static_cast<real>(cur[3]);
      } else if (kind_ == ControllerKind::lee_velocity) {
        for (int k = 0; k < 3; ++k) a[k] = static_cast<real>(cur[k] * spec_.max_speed_m_s);
        a[3] = static_cast<real>(cur[3] * spec_.max_yaw_rate_rad_s);
      } else {
        for (int k = 0; k < kActionDim; ++k) a[k] = static_cast<real>(cur[k]);
      }
      if (flat_) a[2] = kind_ == ControllerKind::lee_position ? sim_->altitude_m() : 0;
    }
    sim_->step(sim_actions_.data());
    ++infos_.steps;
    for (int env = 0; env < num_envs_; ++env) {
      const std::size_t i = static_cast<std::size_t>(env);
      ++episode_step_[i];
      const int why = evaluate_terminations(env);
      const bool success = why == 1, crash = why == 2, timeout = why == 3;
      const float r = custom_terms::reward(spec_, res_, seen(env), position(env), success, crash, &action_[i * kActionDim],
                                           &action_prev_[i * kActionDim], &prev_dist_[i * spec_.rewards.size()]);
      rewards_[i] = r;
      terminations_[i] = (success || crash) ? 1 : 0;
      truncations_[i] = timeout ? 1 : 0;
      episode_reward_[i] += static_cast<double>(r);
      ended_[i] = why != 0 ? 1 : 0;
      if (ended_[i]) custom_terms::count_episode(why, episode_reward_[i], infos_);
    }
    reset_ended();  // auto-reset: the rows below are the new episodes' first observations
    for (int env = 0; env < num_envs_; ++env) write_obs(env);
  }

  bool scripted_actions(float* actions) const override {
    if (!spec_.scripted) return false;
    for (int env = 0; env < num_envs_; ++env) {
      float* a = actions + static_cast<std::size_t>(env) * kActionDim;
      spec_.scripted(spec_, position(env), seen(env), a);
      if (flat_) a[2] = 0.0f;
    }
    return true;
  }

  Vec3 object_centre(int env, const std::string& name) const override {
    return custom_terms::object_centre(spec_, centres_, num_envs_, env, name);
  }

  int evaluate_terminations(int env) const override {
    return custom_terms::evaluate_terminations(spec_, res_, seen(env), position(env), !flat_, crash_or_out(env),
                                               episode_step_[static_cast<std::size_t>(env)] >= len_);
  }

 private:
  /// The objects' centres as the terms see them (at the flight altitude where it is held).
  const Vec3* seen(int env) const {
    return spec_.objects.empty() ? nullptr : &seen_[static_cast<std::size_t>(env) * spec_.objects.size()];
  }

  // After the Simulator's reset of env: the randomisation terms move the objects and the solid
  // ones are written into their box slots (one set_obstacle_boxes call: the images re-render once).
  void on_reset(int env) override {
    const std::size_t i = static_cast<std::size_t>(env), no = spec_.objects.size();
    Vec3* c = no ? &centres_[i * no] : nullptr;
    custom_terms::randomize_objects(spec_, res_, rng_[i], c);
    boxes_.clear();  // capacity reserved at creation: no heap
    for (std::size_t k = 0; k < no; ++k) {
      seen_[i * no + k] = flat_ ? Vec3(c[k][0], c[k][1], sim_->altitude_m()) : c[k];
      if (slot_class_[k] < 0) continue;
      ObstacleBox b;
      b.asset_class = slot_class_[k];
      b.center_w = c[k];
      b.half_extents_m = spec_.objects[k].half_extents_m;
      boxes_.push_back(b);
    }
    // Checked at creation (positive finite extents, finite centres, one box slot per solid
    // object; make_custom_task refuses a task whose first reset was refused), so this holds; a
    // refusal leaves last_error() set and the objects where they were, and is latched here.
    if (!sim_->set_obstacle_boxes(env, boxes_.data(), static_cast<int>(boxes_.size()))) boxes_refused_ = true;
    custom_terms::reset_progress(spec_, res_, seen(env), position(env), &prev_dist_[i * spec_.rewards.size()]);
    for (int a = 0; a < kActionDim; ++a) action_[i * kActionDim + a] = action_prev_[i * kActionDim + a] = 0;
  }

  void write_obs(int env) override {
    const std::size_t i = static_cast<std::size_t>(env);
    custom_terms::ObsInput in;
    in.position_w = position(env);
    const real* q = sim_->base_quat_xyzw() + 4 * i;
    in.orientation_wb = Quat(q[3], q[0], q[1], q[2]);  // wxyz constructor
    for (int k = 0; k < 3; ++k) in.linvel_b[k] = sim_->base_lin_vel_b()[3 * i + k];
    for (int k = 0; k < 3; ++k) in.angvel_b[k] = sim_->base_ang_vel_b()[3 * i + k];
    in.action = &action_[i * kActionDim];
    if (sim_->num_range_images() > 0) in.image = sim_->range_image(env, 0);
    custom_terms::write_obs(spec_, res_, seen(env), in, &obs_[i * static_cast<std::size_t>(obs_dim_)]);
  }

  CustomTaskSpec spec_;
  custom_terms::Resolved res_;
  std::vector<int> slot_class_;  // per object: its asset class index (solid), -1 (region)
  ControllerKind kind_ = ControllerKind::lee_position;
  bool flat_ = false;
  std::vector<Vec3> centres_, seen_;  // envs x objects: drawn centres, and as the terms see them
  std::vector<float> prev_dist_;      // envs x reward terms (progress_to)
  std::vector<float> action_, action_prev_;
  std::vector<ObstacleBox> boxes_;    // one reset's solid objects
  bool boxes_refused_ = false;        // a set_obstacle_boxes refusal (Simulator::last_error says why)

 public:
  bool boxes_refused() const { return boxes_refused_; }
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
  return make_custom_task(config, spec, Backend::rigid, error);
}

std::unique_ptr<Task> make_custom_task(const WorldConfig& config, const CustomTaskSpec& spec, Backend backend, std::string& error) {
  if (!custom_terms::check_spec(spec, error)) return nullptr;
  const bool planar = backend == Backend::planar;
  const std::string where = planar ? "simulator planar: custom task " + spec.id + ": " : "custom task '" + spec.id + "': ";
  WorldConfig wc;
  std::vector<int> slot_class;
  const std::vector<ControllerKind> allowed =
      planar ? std::vector<ControllerKind>{ControllerKind::lee_position, ControllerKind::lee_velocity}
             : std::vector<ControllerKind>{ControllerKind::lee_position, ControllerKind::lee_velocity, ControllerKind::lee_attitude};
  const char* names = planar ? "lee_position_control or lee_velocity_control (the fixed-altitude multirotor), or use simulator: rigid"
                             : "lee_position_control, lee_velocity_control or lee_attitude_control";
  if (!custom_terms::prepare_config(config, spec, allowed, names, where, wc, slot_class, error)) return nullptr;
  task_support::TaskNeeds needs;
  needs.id = spec.id;
  needs.prefix = where;
  for (const ObservationTerm& t : spec.observations)
    if (t.kind == ObsTermKind::image_pool) {
      needs.image = true;
      if (t.rows * t.cols > needs.image_rows * needs.image_cols) {
        needs.image_rows = t.rows;
        needs.image_cols = t.cols;
      }
    }
  std::unique_ptr<Simulator> s = task_support::make_task_simulator(wc, backend, needs, error);
  if (!s) return nullptr;
  std::unique_ptr<CustomTask> t(new CustomTask(std::move(s), spec, std::move(slot_class)));
  if (t->boxes_refused()) {  // the constructor's reset placed the objects: a refusal is a bad spec
    error = where + t->simulator().last_error();
    return nullptr;
  }
  return t;
}

const CustomTaskView* custom_task_view(const Task& task) { return dynamic_cast<const CustomTaskView*>(&task); }

}  // namespace kestrel::sim
