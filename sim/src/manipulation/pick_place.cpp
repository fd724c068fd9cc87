// LeIsaac's SO-101 pick-and-place as one environment (sim/pick_place.hpp).
#include "kestrel/sim/pick_place.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/state_hash.hpp"
#include "../backends/articulated_batch.hpp"

namespace kestrel::sim {

namespace dy = kestrel::dynamics;

namespace {
constexpr real kContactMargin_m = 0.002_r;  // speculative contacts (contact.hpp)
constexpr int kBoxParts = 5;  // floor, walls at -x, +x, -y, +y
const char* const kJointNames[PickPlaceWorld::kJoints] = {"shoulder_pan", "shoulder_lift", "elbow_flex",
                                                          "wrist_flex",   "wrist_roll",    "gripper"};
// Contact keys (WarmStart's names between steps), one range per kind of pair, far apart.
constexpr std::int32_t kKeyArmCube = 0;          // + 16 x arm shape
constexpr std::int32_t kKeyArmTable = 100000;    // collide_halfspace: (first + shape) x 8 + point
constexpr std::int32_t kKeyCubeTable = 200000;
constexpr std::int32_t kKeyCubeBox = 300000;     // + 16 x part
constexpr std::int32_t kKeyArmBox = 400000;      // + 16 x (8 x arm shape + part)
}  // namespace

struct PickPlaceWorld::Impl {
  RobotMultibody model;  // the arm's bodies, then the cube (a free body from the world)
  dy::MultibodyData<kMaxRobotBodies> data;
  dy::ConstraintData<kMaxRobotBodies, kMaxContacts> cd;
  legged_batch::Warm warm;  // the batched step's warm start (its first 96 rows; more start from zero)
  dy::ContactPoint contacts[kMaxContacts];
  std::vector<dy::CollisionShape> arm_shapes;  // sized at init
  std::vector<real> arm_radius;                 // bounding_radius of each, at init
  std::vector<Vec3> arm_centre_w;               // each one's centre at the step's poses (collide())
  real cube_radius = 0;
  real box_radius[kBoxParts] = {};                      // the box's parts' (world shapes: their centre is p_b)
  Vec3 box_centre_w = Vec3::Zero();             // a sphere around all five parts (place_box)
  real box_all_radius = 0;
  dy::CollisionShape cube;
  dy::CollisionShape box[kBoxParts];            // world shapes (body -1), placed at reset
  dy::HalfSpace table;
  dy::ConstraintParams params;
};

PickPlaceWorld::PickPlaceWorld() : impl_(std::make_unique<Impl>()) {}
PickPlaceWorld::~PickPlaceWorld() = default;

bool PickPlaceWorld::init(const PickPlaceConfig& c, std::uint64_t seed, std::uint32_t env_index, std::string& error) {
  PickPlaceConfig cfg = c;
  if (cfg.robot_file.empty()) cfg.robot_file = models_dir() + "/so101/so101.xml";
  const std::string pre = "pick_place: ";
  auto positive = [&](real v, const char* field) {
    if (v > 0 && std::isfinite(v)) return true;
    error = pre + field + ": expected a positive finite number (got " + std::to_string(v) + ")";
    return false;
  };
  if (!positive(cfg.dt_s, "dt_s") || !positive(cfg.cube_half_m, "cube_half_m") || !positive(cfg.cube_mass_kg, "cube_mass_kg") ||
      !positive(cfg.box_inner_half_m, "box_inner_half_m") || !positive(cfg.box_wall_m, "box_wall_m") ||
      !positive(cfg.box_height_m, "box_height_m") || !positive(cfg.success_xy_m, "success_xy_m") ||
      !positive(cfg.success_height_m, "success_height_m"))
    return false;
  if (cfg.decimation < 1 || cfg.solver_iterations < 1) {
    error = pre + "decimation, solver_iterations: expected >= 1";
    return false;
  }
  if (!(cfg.randomize_xy_m >= 0) || !all_finite(cfg.cube_pos_w) || !all_finite(cfg.box_pos_w)) {
    error = pre + "randomize_xy_m (>= 0), cube_pos_w, box_pos_w: expected finite numbers";
    return false;
  }
  ArticulatedRobot robot;
  if (!load_robot_model(cfg.robot_file, robot, error)) return false;
  const RobotMultibody& arm = robot.multibody;
  const std::string fpre = pre + cfg.robot_file + ": ";
  if (arm.joint[0] == dy::JointType::free) {
    error = fpre + "the arm must stand on a fixed base (its first body has a free joint)";
    return false;
  }
  // The six joints by name, in q order 0..5 (the file's order must be LeRobot's).
  for (int j = 0; j < kJoints; ++j) {
    int found = -1;
    for (int b = 0; b < arm.num_bodies; ++b)
      if (robot.joint_names[static_cast<std::size_t>(b)] == kJointNames[j]) found = b;
    if (found < 0 || arm.q_index[found] != j || arm.dof_index[found] != j || arm.joint[found] != dy::JointType::revolute) {
      error = fpre + "expected the revolute joint \"" + kJointNames[j] + "\" as coordinate " + std::to_string(j) +
              " (the SO-101's six joints: shoulder_pan, shoulder_lift, elbow_flex, wrist_flex, wrist_roll, gripper)";
      return false;
    }
    home_[j] = robot.has_home ? robot.home_q[static_cast<std::size_t>(j)] : real(0);
    lower_[j] = arm.has_limit[found] ? arm.q_min[found] : -kPi;
    upper_[j] = arm.has_limit[found] ? arm.q_max[found] : kPi;
    effort_[j] = arm.effort_limit[found] > 0 ? arm.effort_limit[found] : real(1e30);
    const bool grip = j == kJoints - 1;
    kp_[j] = grip ? cfg.gripper_kp_Nm_rad : cfg.arm_kp_Nm_rad;
    kd_[j] = grip ? cfg.gripper_kd_Nms_rad : cfg.arm_kd_Nms_rad;
    if (!(kp_[j] >= 0) || !(kd_[j] >= 0)) {
      error = pre + "arm/gripper kp, kd: expected >= 0";
      return false;
    }
  }
  if (arm.num_dofs != kJoints) {
    error = fpre + "expected exactly six degrees of freedom (got " + std::to_string(arm.num_dofs) + ")";
    return false;
  }
  tcp_body_ = find_body(robot, "gripper_frame");
  if (tcp_body_ < 0) {
    error = fpre + "no body named \"gripper_frame\" (the tool centre point)";
    return false;
  }
  Impl& im = *impl_;
  im.arm_shapes.clear();
  for (const RobotGeom& g : robot.geoms) {
    if (g.body < 0) continue;  // the base, welded to the table
    dy::CollisionShape s;
    if (!to_collision_shape(g, s)) {
      error = fpre + "geom \"" + g.name + "\": a plane on a moving body is not supported";
      return false;
    }
    if (s.type == dy::ShapeType::convex) {
      error = fpre + "geom \"" + g.name + "\": a collision mesh (meshes collide with the ground only; the arm needs primitives)";
      return false;
    }
    if (g.name == "fixed_jaw_pad") pad_body_[0] = g.body;
    if (g.name == "moving_jaw_pad") pad_body_[1] = g.body;
    im.arm_shapes.push_back(s);
    im.arm_radius.push_back(dy::bounding_radius(s));
  }
  im.arm_centre_w.assign(im.arm_shapes.size(), Vec3::Zero());
  if (pad_body_[0] < 0 || pad_body_[1] < 0) {
    error = fpre + "expected the geoms \"fixed_jaw_pad\" and \"moving_jaw_pad\" (the gripper's pads)";
    return false;
  }
  // The forest: the arm, then the cube as a free body of its own.
  im.model = arm;
  RobotMultibody& m = im.model;
  cube_body_ = m.num_bodies;
  if (cube_body_ >= kMaxRobotBodies) {
    error = fpre + "too many bodies to add the cube (at most " + std::to_string(kMaxRobotBodies - 1) + ")";
    return false;
  }
  m.num_bodies += 1;
  m.parent[cube_body_] = -1;
  m.joint[cube_body_] = dy::JointType::free;
  m.X_tree[cube_body_] = dy::Transform();
  const real side = 2 * cfg.cube_half_m;
  m.body[cube_body_].mass = cfg.cube_mass_kg;
  m.body[cube_body_].com = Vec3::Zero();
  m.body[cube_body_].inertia_com = Vec3::Constant(cfg.cube_mass_kg * side * side / 6).asDiagonal();
  if (dy::finish_model(m) != Status::ok || m.num_q != kJoints + 7) {
    error = fpre + "the arm and the cube do not make a valid model";
    return false;
  }
  im.cube = dy::CollisionShape();
  im.cube.body = cube_body_;
  im.cube.type = dy::ShapeType::box;
  im.cube.size = Vec3::Constant(cfg.cube_half_m);
  im.cube.friction = cfg.cube_friction;
  im.cube_radius = dy::bounding_radius(im.cube);
  im.table = dy::HalfSpace();
  im.table.friction = cfg.table_friction;
  for (dy::CollisionShape& b : im.box) {
    b = dy::CollisionShape();
    b.body = -1;
    b.type = dy::ShapeType::box;
    b.friction = cfg.box_friction;
  }
  im.params = dy::ConstraintParams();
  im.params.iterations = cfg.solver_iterations;
  im.params.poses_current = true;  // step() runs forward_kinematics into im.cd for its collisions
  batch_ok_ = legged_batch::eligible(im.model);
  cfg_ = cfg;
  robot_ = std::move(robot);
  rng_ = RngStream(seed, env_index, kPurposeObjectPose);
  reset();
  return true;
}

void PickPlaceWorld::reset() {
  Impl& im = *impl_;
  // randomize_object_uniform: four draws always (the stream's position does not depend on values).
  const real r = cfg_.randomize_xy_m;
  const real cx = rng_.uniform(-r, r), cy = rng_.uniform(-r, r), bx = rng_.uniform(-r, r), by = rng_.uniform(-r, r);
  place_box(Vec3(cfg_.box_pos_w[0] + bx, cfg_.box_pos_w[1] + by, 0));
  for (int j = 0; j < kJoints; ++j) {
    q_[j] = target_[j] = home_[j];
    qd_[j] = 0;
  }
  im.warm.count = 0;
  set_cube_pose(Vec3(cfg_.cube_pos_w[0] + cx, cfg_.cube_pos_w[1] + cy, cfg_.cube_half_m), Vec4(0, 0, 0, 1));
}

void PickPlaceWorld::place_box(const Vec3& box_c) {
  Impl& im = *impl_;
  const real in = cfg_.box_inner_half_m, w = cfg_.box_wall_m, h = cfg_.box_height_m;
  im.box[0].p_b = box_c + Vec3(0, 0, w / 2);
  im.box[0].size = Vec3(in + w, in + w, w / 2);
  for (int s = 0; s < 2; ++s) {
    const real sign = s == 0 ? real(-1) : real(1);
    im.box[1 + s].p_b = box_c + Vec3(sign * (in + w / 2), 0, h / 2);
    im.box[1 + s].size = Vec3(w / 2, in + w, h / 2);
    im.box[3 + s].p_b = box_c + Vec3(0, sign * (in + w / 2), h / 2);
    im.box[3 + s].size = Vec3(in, w / 2, h / 2);
  }
  im.box_centre_w = box_c + Vec3(0, 0, h / 2);
  im.box_all_radius = 0;
  for (int p = 0; p < kBoxParts; ++p) {
    im.box_radius[p] = dy::bounding_radius(im.box[p]);
    im.box_all_radius = std::max(im.box_all_radius, (im.box[p].p_b - im.box_centre_w).norm() + im.box_radius[p]);
  }
  state_.box_pos_w = box_c;
}

void PickPlaceWorld::set_box_position(const Vec3& p_w) {
  if (!all_finite(p_w)) return;
  place_box(p_w);
  // The contacts against the box's parts were found at the old place: no warm start from them.
  impl_->warm.count = 0;
}

void PickPlaceWorld::set_cube_pose(const Vec3& p_w, const Vec4& quat_xyzw) {
  for (int a = 0; a < 3; ++a) q_[kJoints + a] = p_w[a];
  const real n = quat_xyzw.norm();
  for (int a = 0; a < 4; ++a) q_[kJoints + 3 + a] = quat_xyzw[a] / n;
  for (int a = 0; a < 6; ++a) qd_[kJoints + a] = 0;
  impl_->warm.count = 0;
  grip_force_N_ = 0;
  num_contacts_ = 0;
  refresh();
}

void PickPlaceWorld::refresh() {
  Impl& im = *impl_;
  dy::forward_kinematics(im.model, im.data, q_, im.cd.X_world);
  const dy::Transform& X = im.cd.X_world[tcp_body_];
  state_.tcp_R_w = X.E.transpose();
  state_.tcp_pos_w = X.r;
  state_.cube_pos_w = Vec3(q_[kJoints], q_[kJoints + 1], q_[kJoints + 2]);
  state_.cube_quat_xyzw = Vec4(q_[kJoints + 3], q_[kJoints + 4], q_[kJoints + 5], q_[kJoints + 6]);
}

void PickPlaceWorld::set_targets(const real* joint_targets_rad) {
  for (int j = 0; j < kJoints; ++j)
    if (std::isfinite(joint_targets_rad[j])) target_[j] = std::min(std::max(joint_targets_rad[j], lower_[j]), upper_[j]);
}

void PickPlaceWorld::servo_torques(real* tau, real* kp, real* kd) const {
  for (int k = 0; k < impl_->model.num_dofs; ++k) tau[k] = kp[k] = kd[k] = 0;
  for (int j = 0; j < kJoints; ++j) {
    const real t = kp_[j] * (target_[j] - q_[j]) - kd_[j] * qd_[j];
    tau[j] = std::min(std::max(t, -effort_[j]), effort_[j]);
    if (std::fabs(t) < effort_[j]) {  // unclipped: the servo's gains act implicitly (contact.hpp)
      kp[j] = kp_[j];
      kd[j] = kd_[j];
    }
  }
}

int PickPlaceWorld::collide() {
  Impl& im = *impl_;
  const dy::Transform* X = im.cd.X_world;
  const dy::Transform world;
  int n = 0;
  auto room = [&]() { return std::max(0, kMaxContacts - n); };
  auto take = [&](int found) { n += std::min(found, room()); };
  // The broad phase: every moving shape's centre once per step, and a pair's narrow phase
  // (collide_shapes) only where collide_shapes' own bounding-sphere test, the same expression on
  // the same centres, would not reject it, so the contacts are the ones it gives without this (a
  // standing arm's 15 shapes against the cube and the box's 5 parts, 90 pairs, ask for a few).
  // Against the table collide_halfspace culls by itself.
  const int ns = static_cast<int>(im.arm_shapes.size());
  Vec3 c_cube;
  Mat3 R_unused;
  dy::shape_pose(im.cube, X[cube_body_], c_cube, R_unused);
  for (int i = 0; i < ns; ++i) dy::shape_pose(im.arm_shapes[static_cast<std::size_t>(i)], X[im.arm_shapes[static_cast<std::size_t>(i)].body],
                                               im.arm_centre_w[static_cast<std::size_t>(i)], R_unused);
  auto near = [&](const Vec3& ca, real ra, const Vec3& cb, real rb) { return !((ca - cb).norm() > ra + rb + kContactMargin_m); };
  // Pair kinds in the order of their key ranges, each kind's pairs in ascending keys, so the list
  // ascends (what the batched step needs to match contacts across worlds; the scalar step takes
  // the same list, so both give the same bits).
  for (int i = 0; i < ns; ++i) {
    const std::size_t si = static_cast<std::size_t>(i);
    const dy::CollisionShape& s = im.arm_shapes[si];
    if (near(im.arm_centre_w[si], im.arm_radius[si], c_cube, im.cube_radius))
      take(dy::collide_shapes(s, X[s.body], im.cube, X[cube_body_], kContactMargin_m, im.contacts + n, room(), kKeyArmCube + 16 * i));
  }
  for (int i = 0; i < ns; ++i)
    take(dy::collide_halfspace(&im.arm_shapes[static_cast<std::size_t>(i)], 1, X, im.table, kContactMargin_m, im.contacts + n, room(),
                               kKeyArmTable / 8 + i));
  take(dy::collide_halfspace(&im.cube, 1, X, im.table, kContactMargin_m, im.contacts + n, room(), kKeyCubeTable / 8));
  for (int p = 0; p < kBoxParts; ++p)
    if (near(c_cube, im.cube_radius, im.box[p].p_b, im.box_radius[p]))
      take(dy::collide_shapes(im.cube, X[cube_body_], im.box[p], world, kContactMargin_m, im.contacts + n, room(), kKeyCubeBox + 16 * p));
  for (int i = 0; i < ns; ++i) {
    const std::size_t si = static_cast<std::size_t>(i);
    const dy::CollisionShape& s = im.arm_shapes[si];
    // The whole box far (its sphere holds every part's; 0.1 mm for rounding).
    if ((im.arm_centre_w[si] - im.box_centre_w).norm() > im.arm_radius[si] + im.box_all_radius + kContactMargin_m + 1e-4_r) continue;
    for (int p = 0; p < kBoxParts; ++p)
      if (near(im.arm_centre_w[si], im.arm_radius[si], im.box[p].p_b, im.box_radius[p]))
        take(dy::collide_shapes(s, X[s.body], im.box[p], world, kContactMargin_m, im.contacts + n, room(), kKeyArmBox + 16 * (8 * i + p)));
  }
  return n;
}

void PickPlaceWorld::physics_step_done(int n) {
  const Impl& im = *impl_;
  num_contacts_ = n;
  real grip = 0;
  for (int c = 0; c < n; ++c) {
    const dy::ContactPoint& ct = im.contacts[c];
    if ((ct.body == pad_body_[0] || ct.body == pad_body_[1]) && ct.body_b == cube_body_)
      grip += std::fabs(im.cd.contact_force_w[c].dot(ct.normal_w));
  }
  grip_force_N_ = grip;
}

Status PickPlaceWorld::step(const real* joint_targets_rad) {
  Impl& im = *impl_;
  set_targets(joint_targets_rad);
  Status st = Status::ok;
  const RobotMultibody& m = im.model;
  for (int k = 0; k < cfg_.decimation; ++k) {
    real tau[kDofs], kp[kDofs], kd[kDofs];
    servo_torques(tau, kp, kd);
    dy::forward_kinematics(m, im.data, q_, im.cd.X_world);
    const int n = collide();
    st = dy::step_constrained(m, im.data, im.cd, q_, qd_, tau, cfg_.dt_s, im.contacts, n, im.params, kp, kd, &im.warm);
    if (st != Status::ok) break;
    physics_step_done(n);
  }
  refresh();
  return st;
}

int PickPlaceWorld::batch_lanes() const { return batch_ok_ ? legged_batch::lanes() : 0; }

std::size_t PickPlaceWorld::batch_scratch_bytes() { return legged_batch::scratch_bytes(); }

int PickPlaceWorld::step_batch(PickPlaceWorld* const* worlds, const real* const* joint_targets_rad, int count, Status* status,
                               void* scratch) {
  if (count <= 0) return 0;
  const PickPlaceWorld& w0 = *worlds[0];
  // A batched step costs its lanes' work whatever the count (lanes past it compute a copy of the
  // first world), about 0.3 of a world's own step per lane (bench_pick_place: 3.8 against 13 us
  // with 16 lanes): fewer than a third of the lanes step faster one at a time.
  const int width = w0.batch_lanes();
  bool together = count <= width && 3 * count >= width && scratch != nullptr;
  for (int l = 1; l < count && together; ++l)
    together = worlds[l]->cfg_.decimation == w0.cfg_.decimation && worlds[l]->cfg_.dt_s == w0.cfg_.dt_s &&
               worlds[l]->cfg_.solver_iterations == w0.cfg_.solver_iterations &&
               worlds[l]->impl_->model.num_dofs == w0.impl_->model.num_dofs;
  if (!together) {  // one at a time, as step()
    for (int l = 0; l < count; ++l) status[l] = worlds[l]->step(joint_targets_rad[l]);
    return 0;
  }
  const RobotMultibody& m = w0.impl_->model;
  dy::ConstraintParams batch_params = w0.impl_->params;  // poses_current: the batch's kinematics, in its scratch
  dy::ConstraintParams alone = w0.impl_->params;
  alone.poses_current = false;  // im.data holds no kinematics of this q: the scalar step computes them
  const real dt = w0.cfg_.dt_s;
  real tau[legged_batch::kMaxLanes][kDofs], kp[legged_batch::kMaxLanes][kDofs], kd[legged_batch::kMaxLanes][kDofs];
  for (int l = 0; l < count; ++l) {
    worlds[l]->set_targets(joint_targets_rad[l]);
    status[l] = Status::ok;
  }
  int batched = 0;
  for (int k = 0; k < w0.cfg_.decimation; ++k) {
    // The worlds still stepping (step() stops a world's action at its first refused physics step).
    PickPlaceWorld* live[legged_batch::kMaxLanes];
    int idx[legged_batch::kMaxLanes];
    int cnt = 0;
    for (int l = 0; l < count; ++l)
      if (status[l] == Status::ok) live[cnt] = worlds[l], idx[cnt++] = l;
    if (cnt == 0) break;
    const real* qs[legged_batch::kMaxLanes];
    dy::Transform* Xs[legged_batch::kMaxLanes];
    for (int l = 0; l < cnt; ++l) {
      qs[l] = live[l]->q_;
      Xs[l] = live[l]->impl_->cd.X_world;
    }
    legged_batch::kinematics(m, qs, cnt, Xs, scratch);
    legged_batch::Lane lanes[legged_batch::kMaxLanes];
    int n[legged_batch::kMaxLanes];
    for (int l = 0; l < cnt; ++l) {
      PickPlaceWorld& w = *live[l];
      w.servo_torques(tau[l], kp[l], kd[l]);
      n[l] = w.collide();
      legged_batch::Lane& ln = lanes[l];
      ln.q = w.q_;
      ln.qd = w.qd_;
      ln.tau = tau[l];
      ln.kp = kp[l];
      ln.kd = kd[l];
      ln.contacts = w.impl_->contacts;
      ln.num_contacts = n[l];
      ln.warm = &w.impl_->warm;
      ln.contact_force_w = w.impl_->cd.contact_force_w;
    }
    unsigned done = legged_batch::step(m, batch_params, dt, lanes, cnt, scratch);
    if (done == 0 && cnt >= 2 && 3 * (cnt / 2) >= width) {
      // Most likely the worlds' contacts together need more slots than the batch has (arms on the
      // table, the box and the cube at once): each half alone, its kinematics computed afresh (the
      // scratch's are the whole call's).
      const int h = cnt / 2;
      done = legged_batch::step(m, alone, dt, lanes, h, scratch);
      done |= legged_batch::step(m, alone, dt, lanes + h, cnt - h, scratch) << h;
    }
    for (int l = 0; l < cnt; ++l) {
      PickPlaceWorld& w = *live[l];
      Impl& im = *w.impl_;
      if ((done >> l) & 1u) {
        ++batched;
      } else {
        const Status st = dy::step_constrained(im.model, im.data, im.cd, w.q_, w.qd_, tau[l], dt, im.contacts, n[l], alone, kp[l], kd[l],
                                               &im.warm);
        if (st != Status::ok) {
          status[idx[l]] = st;
          continue;
        }
      }
      w.physics_step_done(n[l]);
    }
  }
  for (int l = 0; l < count; ++l) worlds[l]->refresh();
  return batched;
}

int PickPlaceWorld::scene_shapes(PickPlaceShape* out, int capacity) const {
  const Impl& im = *impl_;
  int count = 0;
  auto put = [&](const dy::CollisionShape& s, PickPlaceEntity entity, int index) {
    if (count < capacity) {
      out[count].shape = s;
      out[count].X_body = s.body >= 0 ? im.cd.X_world[s.body] : dy::Transform();
      out[count].entity = entity;
      out[count].index = index;
    }
    ++count;
  };
  for (std::size_t i = 0; i < im.arm_shapes.size(); ++i) put(im.arm_shapes[i], PickPlaceEntity::robot, static_cast<int>(i));
  put(im.cube, PickPlaceEntity::cube, 0);
  for (int p = 0; p < kBoxParts; ++p) put(im.box[p], PickPlaceEntity::box, p);
  return count;
}

dy::Transform PickPlaceWorld::body_pose(int body) const {
  if (body < 0 || body >= impl_->model.num_bodies) return dy::Transform();
  return impl_->cd.X_world[body];
}

int PickPlaceWorld::solver_iterations_used() const { return impl_->cd.iterations_used; }

bool PickPlaceWorld::cube_in_box() const {
  const Vec3 d = state_.cube_pos_w - state_.box_pos_w;
  return std::fabs(d[0]) < cfg_.success_xy_m && std::fabs(d[1]) < cfg_.success_xy_m && state_.cube_pos_w[2] < cfg_.success_height_m;
}

real PickPlaceWorld::solve_tcp(const Vec3& p_w, real yaw_rad, const real* q_start, real* q_out) const {
  Impl& im = *impl_;
  real q[kJoints + 7];
  std::memcpy(q, q_, sizeof(q));
  for (int j = 0; j < kJoints; ++j) q[j] = q_start[j];
  // Pointing straight down: the gripper's z (fingers along its -z) up the world's z, its x (the
  // pads' normal) at yaw_rad about the vertical.
  const real c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  Mat3 R;
  R << c, -s, 0, s, c, 0, 0, 0, 1;
  dy::IkParams p;
  p.iterations = 30;
  // Position first: where the wrist cannot point straight down (far reach, wrist_flex at its
  // limit) a tilt of 0.03 rad costs what 1 mm of position does.
  p.orientation_weight = 0.03_r;
  p.damping = 0.01_r;
  dy::IkResult res;
  if (dy::solve_ik(im.model, im.data, q, tcp_body_, Vec3::Zero(), p_w, &R, p, res) != Status::ok) {
    for (int j = 0; j < kJoints; ++j) q_out[j] = q_start[j];
    return std::numeric_limits<real>::infinity();
  }
  for (int j = 0; j < kJoints; ++j) q_out[j] = q[j];
  return res.position_error_m;
}

std::uint64_t PickPlaceWorld::state_hash() const {
  Fnv1a f;
  f.bytes(q_, sizeof(q_));
  f.bytes(qd_, sizeof(qd_));
  return f.h;
}

// ----------------------------------------------------------------------------------------------

ScriptedPickPlace::ScriptedPickPlace(const PickPlaceWorld& world) : w_(world) { reset(); }

void ScriptedPickPlace::reset() {
  for (int j = 0; j < PickPlaceWorld::kJoints; ++j) q_ik_[j] = w_.joint_pos()[j];
  // The pads' normal along the world's x or y, whichever turns the wrist least from where it is
  // (the cube's faces are at 0, 90, 180 and 270 degrees).
  const Vec3 x = w_.state().tcp_R_w.col(0);
  const real now = std::atan2(x[1], x[0]);
  yaw_ = std::round(now / (kPi / 2)) * (kPi / 2);
  grip_ = gripper_open_rad;
  from_w_ = to_w_ = w_.state().tcp_pos_w;
  start_phase(kApproach);
}

void ScriptedPickPlace::start_phase(int phase) {
  phase_ = phase;
  tick_ = 0;
  const PickPlaceConfig& c = w_.config();
  const real control_dt = c.dt_s * real(c.decimation);
  auto ticks = [&](real seconds) { return std::max(1, static_cast<int>(std::lround(seconds / control_dt))); };
  from_w_ = to_w_;
  const Vec3 cube = w_.state().cube_pos_w, box = w_.state().box_pos_w;
  // The fixed jaw does not move: its pad's face is cube_half from the tool centre point, so the
  // gripper comes down beside the cube by fixed_jaw_clearance_m (away from the fixed jaw, along the
  // pads' normal, the gripper's x) and the moving jaw then pushes the cube onto the fixed pad.
  const real dx = fixed_jaw_clearance_m * std::cos(yaw_), dy = fixed_jaw_clearance_m * std::sin(yaw_);
  auto grasp_xy = [&](const Vec3& p) { return Vec3(p[0] - dx, p[1] - dy, 0); };
  const real grasp_z = c.cube_half_m + grasp_depth_m;
  const real carry_z = lift_height_m;
  switch (phase) {
    case kApproach: to_w_ = grasp_xy(cube) + Vec3(0, 0, grasp_z + 0.06_r); ticks_ = ticks(1.0_r); break;
    case kDescend: to_w_ = grasp_xy(cube) + Vec3(0, 0, grasp_z); ticks_ = ticks(0.6_r); break;
    case kClose: ticks_ = ticks(0.5_r); break;
    case kLift: to_w_ = Vec3(from_w_[0], from_w_[1], carry_z); ticks_ = ticks(0.6_r); break;
    case kCarry: to_w_ = Vec3(box[0], box[1], carry_z); ticks_ = ticks(1.0_r); break;
    case kLower: to_w_ = Vec3(box[0], box[1], c.box_wall_m + c.cube_half_m + 0.02_r); ticks_ = ticks(0.6_r); break;
    case kOpen: ticks_ = ticks(0.3_r); break;
    case kRetreat: to_w_ = Vec3(from_w_[0], from_w_[1], from_w_[2] + 0.06_r); ticks_ = ticks(0.4_r); break;
    default: ticks_ = 1; break;
  }
}

void ScriptedPickPlace::act(real* out) {
  if (phase_ < kDone) {
    ++tick_;
    const real u = std::min(real(1), real(tick_) / real(ticks_));
    const real sm = u * u * (3 - 2 * u);  // a cubic time law: no jump in speed at either end
    const Vec3 p = from_w_ + sm * (to_w_ - from_w_);
    if (phase_ == kClose) grip_ = gripper_open_rad + sm * (gripper_close_rad - gripper_open_rad);
    if (phase_ == kOpen) grip_ = gripper_close_rad + sm * (gripper_open_rad - gripper_close_rad);
    (void)w_.solve_tcp(p, yaw_, q_ik_, q_ik_);
    if (tick_ >= ticks_) start_phase(phase_ + 1);
  }
  for (int j = 0; j < PickPlaceWorld::kJoints - 1; ++j) out[j] = q_ik_[j];
  out[PickPlaceWorld::kJoints - 1] = grip_;
}

}  // namespace kestrel::sim
