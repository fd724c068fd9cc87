// The Simulator interface: backend selection, shared views, push_robots, the scripted setpoint
// policy and the registry entries. The backends live in rigid.cpp and planar.cpp (this folder).
#include "kestrel/sim/simulator.hpp"

#include <cmath>
#include <cstdlib>
#include <cstring>

#include "kestrel/controllers/velocity_steering.hpp"
#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/registry.hpp"

namespace kestrel::sim {

std::unique_ptr<Simulator> make_rigid_simulator(const WorldConfig& config, std::string& error);
std::unique_ptr<Simulator> make_planar_simulator(const WorldConfig& config, std::string& error);
std::unique_ptr<Simulator> make_articulated_simulator(const WorldConfig& config, std::string& error);

const char* backend_name(Backend b) { return b == Backend::planar ? "planar" : "rigid"; }

bool backend_from_name(const std::string& name, Backend& out) {
  if (name == "rigid") out = Backend::rigid;
  else if (name == "planar") out = Backend::planar;
  else return false;
  return true;
}

bool resolve_backend(const WorldConfig& config, Backend& out, std::string& error) {
  const char* env = std::getenv("KESTREL_SIMULATOR");
  if (env != nullptr && env[0] != '\0') {
    if (backend_from_name(env, out)) return true;
    error = std::string("KESTREL_SIMULATOR: unknown simulator \"") + env + "\"; allowed: rigid, planar";
    return false;
  }
  if (config.simulator.backend.empty()) {
    out = Backend::rigid;
    return true;
  }
  if (backend_from_name(config.simulator.backend, out)) return true;
  error = "simulator: unknown simulator \"" + config.simulator.backend + "\"; allowed: rigid, planar";
  return false;
}

std::unique_ptr<Simulator> make_simulator(const WorldConfig& config, Backend backend, std::string& error) {
  if (config.robot.kind == robots::RobotKind::articulated) {
    if (backend == Backend::planar) {
      error = "simulator planar: robot " + config.robot.name +
              " is articulated (joints from a robot file); Box2D's planar world holds no joint trees; use simulator: rigid";
      return nullptr;
    }
    return make_articulated_simulator(config, error);
  }
  return backend == Backend::planar ? make_planar_simulator(config, error) : make_rigid_simulator(config, error);
}

std::unique_ptr<Simulator> make_simulator(const WorldConfig& config, std::string& error) {
  Backend b = Backend::rigid;
  if (!resolve_backend(config, b, error)) return nullptr;
  return make_simulator(config, b, error);
}

Simulator::~Simulator() = default;

bool articulated_only_randomisation(const SimulatorConfig& sc) {
  return sc.friction_min != -1 || sc.friction_max != -1 || sc.restitution_min != -1 || sc.restitution_max != -1 ||
         sc.joint_armature_min_kg_m2 != -1 || sc.joint_armature_max_kg_m2 != -1 || sc.max_push_force_N != 0;
}

void Simulator::allocate_views(const WorldConfig& cfg, int action_dim, int lidar_beams) {
  cfg_ = cfg;
  num_envs_ = cfg.env.num_envs;
  robots_per_env_ = cfg.robot.robots_per_env;
  action_dim_ = action_dim;
  decimation_ = std::max(1, static_cast<int>(std::floor(cfg.env.num_physics_steps_per_env_step_mean + 0.5_r)));
  lidar_beams_ = lidar_beams;
  const std::size_t n = static_cast<std::size_t>(num_robots());
  actions_.assign(n * static_cast<std::size_t>(action_dim), 0);
  pos_w_.assign(3 * n, 0);
  quat_xyzw_.assign(4 * n, 0);
  euler_xyz_.assign(3 * n, 0);
  lin_vel_b_.assign(3 * n, 0);
  lin_vel_w_.assign(3 * n, 0);
  ang_vel_b_.assign(3 * n, 0);
  contact_w_.assign(3 * n, 0);
  wrench_b_.assign(6 * n, 0);
  target_w_.assign(3 * n, 0);
  crashed_.assign(n, 0);
  reset_buf_.assign(static_cast<std::size_t>(num_envs_), 0);
  added_mass_kg_.assign(n, 0);
  com_bias_b_m_.assign(3 * n, 0);
  dr_friction_.assign(n, -1);     // not randomised (articulated robots' set-up draws them)
  dr_restitution_.assign(n, -1);
  dr_armature_.clear();           // (robots x 0) without joints
  terrain_levels_.assign(static_cast<std::size_t>(num_envs_), 0);
  terrain_types_.assign(static_cast<std::size_t>(num_envs_), 0);
  env_origins_w_.assign(3 * static_cast<std::size_t>(num_envs_), 0);
  motor_scale_.assign(n, 1);
  gain_scale_.assign(n, 1);
  lidar_.assign(n * static_cast<std::size_t>(lidar_beams), 0);
  rng_push_.resize(static_cast<std::size_t>(num_envs_));
  for (int e = 0; e < num_envs_; ++e) rng_push_[static_cast<std::size_t>(e)] = RngStream(cfg.seed, cfg.env.global_env(e), kPurposePush);
}

void Simulator::write_euler_view(std::size_t i) const {
  const real* q = &quat_xyzw_[4 * i];
  const Vec3 e = euler_xyz_two_pi(quat_from_xyzw(q[0], q[1], q[2], q[3]));
  for (int k = 0; k < 3; ++k) euler_xyz_[3 * i + k] = wrap_pi(e[k]);
}

void Simulator::write_state_view(std::size_t i, const RigidBodyState& s, bool with_euler) {
  for (int k = 0; k < 3; ++k) pos_w_[3 * i + k] = s.position_w[k];
  const auto& c = s.orientation_wb.coeffs();  // Eigen stores x, y, z, w
  for (int k = 0; k < 4; ++k) quat_xyzw_[4 * i + k] = c[k];
  if (with_euler) write_euler_view(i);
  const Vec3 vb = rotate_inverse(s.orientation_wb, s.linvel_w);
  for (int k = 0; k < 3; ++k) lin_vel_b_[3 * i + k] = vb[k];
  for (int k = 0; k < 3; ++k) lin_vel_w_[3 * i + k] = s.linvel_w[k];
  for (int k = 0; k < 3; ++k) ang_vel_b_[3 * i + k] = s.angvel_b[k];
}

void Simulator::step(const real* actions) {
  actions_given_ = actions != nullptr;
  if (actions != nullptr) std::copy(actions, actions + actions_.size(), actions_.begin());
  advance();
  post_physics_step();
}

bool Simulator::reset_root_states(const int* env_ids, int count, const real* pos_w, const real* quat_xyzw,
                                  const real* lin_vel_w, const real* ang_vel_w) {
  // The prefix is built only on a refusal: a task resets root states inside its step, which must
  // not allocate.
  const auto pre = [this] { return std::string("simulator ") + backend_name() + ": reset_root_states: "; };
  for (int k = 0; k < count; ++k)
    if (env_ids[k] < 0 || env_ids[k] >= num_envs_)
      return fail(pre() + "env id " + std::to_string(env_ids[k]) + " out of range [0, " + std::to_string(num_envs_) + ")");
  const int rows = count * robots_per_env_;
  for (int j = 0; j < rows; ++j) {
    if (!all_finite(pos_w + 3 * j, 3) || !all_finite(quat_xyzw + 4 * j, 4) || !all_finite(lin_vel_w + 3 * j, 3) ||
        !all_finite(ang_vel_w + 3 * j, 3))
      return fail(pre() + "non-finite value in row " + std::to_string(j));
    const real* q = quat_xyzw + 4 * j;
    const real n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    if (!(std::fabs(n2 - 1) < 1e-3_r)) return fail(pre() + "quaternion of row " + std::to_string(j) + " is not unit length");
  }
  return set_root_states(env_ids, count, pos_w, quat_xyzw, lin_vel_w, ang_vel_w);
}

bool Simulator::set_viewer_camera(const Vec3& position_w, const Vec3& lookat_w) {
  if (!position_w.allFinite() || !lookat_w.allFinite())
    return fail(std::string("simulator ") + backend_name() + ": set_viewer_camera: position and lookat must be finite");
  if (position_w == lookat_w)
    return fail(std::string("simulator ") + backend_name() + ": set_viewer_camera: position and lookat must differ");
  viewer_request_.camera_set = true;
  viewer_request_.camera_position_w = position_w;
  viewer_request_.camera_lookat_w = lookat_w;
  if (viewer_ != nullptr) viewer_->on_viewer_request(viewer_request_);
  return true;
}

void Simulator::draw_debug_vis(bool height_samples, bool contacts) {
  viewer_request_.debug_height_samples = height_samples;
  viewer_request_.debug_contacts = contacts;
  if (viewer_ != nullptr) viewer_->on_viewer_request(viewer_request_);
}

void Simulator::set_viewer(ViewerHooks* viewer) {
  viewer_ = viewer;
  if (viewer_ != nullptr) viewer_->on_viewer_request(viewer_request_);
}

void Simulator::push_robots() {
  const real m = cfg_.simulator.max_push_vel_xy_m_s;
  for (int e = 0; e < num_envs_; ++e) {
    RngStream& rng = rng_push_[static_cast<std::size_t>(e)];
    for (int r = 0; r < robots_per_env_; ++r) {
      // Two draws per robot always, so the stream position does not depend on the values.
      const real vx = rng.uniform(-m, m), vy = rng.uniform(-m, m);
      set_velocity_xy(e, r, vx, vy);
    }
  }
}

real Simulator::lidar_beam_angle(int k) const {
  if (lidar_beams_ <= 1) return 0;
  const real fov = cfg_.simulator.lidar_fov_rad;
  return -fov / 2 + fov * static_cast<real>(k) / static_cast<real>(lidar_beams_ - 1);
}

void scripted_setpoint_actions(const Simulator& sim, real* actions) {
  const int n = sim.num_robots(), ad = sim.action_dim();
  const real* p = sim.base_pos_w();
  const real* t = sim.target_w();
  const real* eul = sim.base_euler_xyz();
  const bool ground = sim.ground_vehicle();
  for (int i = 0; i < n; ++i) {
    real* a = actions + static_cast<std::size_t>(i) * static_cast<std::size_t>(ad);
    for (int k = 0; k < ad; ++k) a[k] = 0;
    if (ground) {
      const SimulatorConfig& sc = sim.config().simulator;
      const real dx = t[3 * i] - p[3 * i], dy = t[3 * i + 1] - p[3 * i + 1];
      const real d = std::sqrt(dx * dx + dy * dy);
      // Pure pursuit of the look-ahead point at ld = min(d, 1 m) on the straight line to the
      // target (the line the placement checked for obstacles): the arc through the rear axle
      // tangent to the heading and through that point has curvature 2 sin(alpha) / ld.
      const real alpha = wrap_pi(std::atan2(dy, dx) - eul[3 * i + 2]);
      // A target behind (|alpha| > 90 deg): pure pursuit's sin(alpha) shrinks towards 0 there and
      // would drive away; turn at full lock towards it instead.
      // A target inside the minimum turning circle (required curvature 2 sin(alpha) / d above
      // tan(max_steering) / L) cannot be reached forwards: back up at opposite lock, which turns
      // the nose towards it.
      const real side = alpha >= 0 ? 1_r : -1_r;
      const real kappa_max = std::tan(sc.max_steering_rad) / sc.wheelbase_m;
      const bool unreachable = d > 1e-3_r && std::fabs(2 * std::sin(alpha) / d) > kappa_max;
      real v = 0, delta = 0;
      if (unreachable && d < 2 / kappa_max) {
        v = -0.5_r;
        delta = -side * sc.max_steering_rad;
      } else if (std::fabs(alpha) > kPi / 2) {
        v = 0.5_r * std::min(sc.max_speed_m_s, 0.8_r * d);
        delta = side * sc.max_steering_rad;
      } else {
        // Speed tapers to zero near the target (stop on it); slower in sharp turns.
        v = std::min(sc.max_speed_m_s, 0.8_r * d) * (std::fabs(alpha) > 1.2_r ? 0.5_r : 1_r);
        const real ld = std::min(d, 1_r);
        delta = ld > 1e-3_r ? std::atan(2 * sc.wheelbase_m * std::sin(alpha) / ld) : 0_r;
      }
      a[0] = v;
      a[1] = clamp(delta, -sc.max_steering_rad, sc.max_steering_rad);
    } else if (std::strcmp(sim.controller_name(), "lee_position_control") == 0) {
      for (int k = 0; k < 3 && k < ad; ++k) a[k] = t[3 * i + k];
    }
  }
}

}  // namespace kestrel::sim
