// Robot files into the core's articulated-body model (sim/articulated_robot.hpp): the shipped Go2,
// ANYmal C and SO-101 arm (models/), their counts, masses, feet, home pose and limits as the files
// give them; the SO-101's gripper pads (which bodies, how far apart at the gripper's limits) and its
// tool frame's forward kinematics against MuJoCo's;
// the Go2 as MJCF and as URDF giving the same tree (same mass matrix); and errors that name the
// file and the problem, leaving the output untouched.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/articulated_robot.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {
const std::string kModels = std::string(KESTREL_SIM_TEST_DIR) + "/../../models";
const std::string kGo2Xml = kModels + "/go2/go2.xml";
const std::string kGo2Urdf = kModels + "/go2/go2.urdf";
const std::string kAnymalXml = kModels + "/anymal_c/anymal_c.xml";
const std::string kSo101Xml = kModels + "/so101/so101.xml";

std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = std::string(::testing::TempDir()) + "/" + name;
  std::ofstream(path) << text;
  return path;
}

ArticulatedRobot load(const std::string& path) {
  ArticulatedRobot r;
  std::string err;
  EXPECT_TRUE(load_robot_model(path, r, err)) << err;
  return r;
}

// M(q) by the core's CRBA.
std::vector<real> mass_matrix(const ArticulatedRobot& r, const std::vector<real>& q) {
  dynamics::MultibodyData<kMaxRobotBodies> d;
  const int n = r.multibody.num_dofs;
  std::vector<real> H(static_cast<std::size_t>(n * n));
  dynamics::crba(r.multibody, d, q.data(), H.data(), n);
  return H;
}

void expect_quadruped(const ArticulatedRobot& r, double mass_kg) {
  EXPECT_EQ(r.multibody.num_bodies, 17);  // base + 4 x (hip, thigh, calf, foot)
  EXPECT_EQ(r.multibody.num_dofs, 18);
  EXPECT_EQ(r.multibody.num_q, 19);
  EXPECT_EQ(r.multibody.joint[0], dynamics::JointType::free);
  int revolute = 0, fixed = 0;
  for (int i = 1; i < r.multibody.num_bodies; ++i) {
    revolute += r.multibody.joint[i] == dynamics::JointType::revolute;
    fixed += r.multibody.joint[i] == dynamics::JointType::fixed;
  }
  EXPECT_EQ(revolute, 12);
  EXPECT_EQ(fixed, 4);  // the feet
  EXPECT_NEAR(r.total_mass_kg, mass_kg, 1e-4);
  real sum = 0;
  for (int i = 0; i < r.multibody.num_bodies; ++i) sum += r.multibody.body[i].mass;
  EXPECT_NEAR(sum, mass_kg, 1e-4);
  ASSERT_EQ(r.foot_bodies.size(), 4u);
  ASSERT_EQ(r.foot_geoms.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(r.multibody.joint[r.foot_bodies[k]], dynamics::JointType::fixed);
    ASSERT_GE(r.foot_geoms[k], 0);
    EXPECT_EQ(r.geoms[static_cast<std::size_t>(r.foot_geoms[k])].type, RobotGeomType::sphere);
    EXPECT_EQ(r.geoms[static_cast<std::size_t>(r.foot_geoms[k])].body, r.foot_bodies[k]);
  }
  EXPECT_NEAR(r.multibody.gravity_w[2], -9.81, 1e-6);
}

const RobotGeom* find_geom(const ArticulatedRobot& r, const std::string& name) {
  for (const RobotGeom& g : r.geoms)
    if (g.name == name) return &g;
  return nullptr;
}

// A geom's rotation and centre in the world at the poses X_world (forward_kinematics).
void geom_pose(const RobotGeom& g, const dynamics::Transform* X_world, Mat3& R, Vec3& p) {
  const Eigen::Quaternion<real> q(g.quat_xyzw_b[3], g.quat_xyzw_b[0], g.quat_xyzw_b[1], g.quat_xyzw_b[2]);
  const dynamics::Transform& X = X_world[g.body];
  R = X.E.transpose() * q.toRotationMatrix();
  p = X.r + X.E.transpose() * g.pos_b;
}

// The SO-101's gripper opening at q: the nearest of the moving pad's 8 corners to the fixed pad's
// inner face, along that face's normal (the fixed pad's +x, towards the moving jaw): negative when
// the pads overlap. `faces_dot`: the two pads' x axes' dot product (1: the inner faces parallel).
double pad_gap(const ArticulatedRobot& r, const std::vector<real>& q, double* faces_dot = nullptr) {
  dynamics::MultibodyData<kMaxRobotBodies> d;
  dynamics::Transform X_world[kMaxRobotBodies];
  dynamics::forward_kinematics(r.multibody, d, q.data(), X_world);
  const RobotGeom& fixed = *find_geom(r, "fixed_jaw_pad");
  const RobotGeom& moving = *find_geom(r, "moving_jaw_pad");
  Mat3 Rf, Rm;
  Vec3 pf, pm;
  geom_pose(fixed, X_world, Rf, pf);
  geom_pose(moving, X_world, Rm, pm);
  const Vec3 n = Rf.col(0);
  const Vec3 face = pf + n * fixed.size[0];
  double gap = 1e9;
  for (int c = 0; c < 8; ++c) {
    const Vec3 s((c & 1 ? 1 : -1) * moving.size[0], (c & 2 ? 1 : -1) * moving.size[1],
                 (c & 4 ? 1 : -1) * moving.size[2]);
    gap = std::min(gap, double((pm + Rm * s - face).dot(n)));
  }
  if (faces_dot) *faces_dot = double(n.dot(Rm.col(0)));
  return gap;
}
}  // namespace

TEST(SimArticulatedRobot, Go2FromMjcf) {
  const ArticulatedRobot r = load(kGo2Xml);
  EXPECT_EQ(r.name, "go2");
  expect_quadruped(r, 15.017);  // go2_description: 6.921 + 4 x (0.678 + 1.152 + 0.154 + 0.04)
  EXPECT_EQ(r.body_names[0], "base");
  EXPECT_EQ(r.body_names[static_cast<std::size_t>(r.foot_bodies[0])], "FL_foot");
  EXPECT_EQ(r.geoms[static_cast<std::size_t>(r.foot_geoms[0])].name, "FL_foot");
  EXPECT_NEAR(r.geoms[static_cast<std::size_t>(r.foot_geoms[0])].size[0], 0.022, 1e-7);
  EXPECT_NEAR(r.geoms[static_cast<std::size_t>(r.foot_geoms[0])].pos_b[0], -0.002, 1e-7);
  // Trunk: a box with the URDF's size, on the base.
  EXPECT_EQ(r.geoms[0].name, "trunk");
  EXPECT_EQ(r.geoms[0].type, RobotGeomType::box);
  EXPECT_EQ(r.geoms[0].body, 0);
  EXPECT_NEAR(r.geoms[0].size[0], 0.1881, 1e-7);
  // FL hip: X_tree at (0.1934, 0.0465, 0), axis x, range, effort, armature, damping, friction.
  const int hip = find_body(r, "FL_hip");
  ASSERT_EQ(hip, 1);
  EXPECT_EQ(r.joint_names[1], "FL_hip_joint");
  EXPECT_NEAR(r.multibody.X_tree[hip].r[0], 0.1934, 1e-7);
  EXPECT_NEAR(r.multibody.X_tree[hip].r[1], 0.0465, 1e-7);
  EXPECT_TRUE(r.multibody.X_tree[hip].E.isIdentity(1e-6));
  EXPECT_NEAR(r.multibody.axis[hip][0], 1, 1e-7);
  EXPECT_TRUE(r.multibody.has_limit[hip]);
  EXPECT_NEAR(r.multibody.q_min[hip], -1.0472, 1e-6);
  EXPECT_NEAR(r.multibody.q_max[hip], 1.0472, 1e-6);
  EXPECT_NEAR(r.multibody.effort_limit[hip], 23.7, 1e-5);
  EXPECT_NEAR(r.multibody.effort_limit[find_body(r, "FL_calf")], 35.55, 1e-5);
  EXPECT_NEAR(r.multibody.armature[hip], 0.01, 1e-8);
  EXPECT_NEAR(r.multibody.damping[hip], 2, 1e-7);
  EXPECT_NEAR(r.multibody.friction_loss[hip], 0.2, 1e-7);
  // The base's inertia as the URDF's full tensor (MuJoCo keeps it as principal axes + moments).
  EXPECT_NEAR(r.multibody.body[0].inertia_com(0, 0), 0.02448, 1e-6);
  EXPECT_NEAR(r.multibody.body[0].inertia_com(0, 2), 0.0014849, 1e-6);
  EXPECT_NEAR(r.multibody.body[0].com[0], 0.021112, 1e-7);
  EXPECT_TRUE(r.multibody.X_tree[0].E.isIdentity(0) && r.multibody.X_tree[0].r.isZero(0));
  // Home: [0 0 0.42 | 0 0 0 1 | FL 0.1 0.8 -1.5 | FR -0.1 0.8 -1.5 | RL 0.1 1 -1.5 | RR -0.1 1 -1.5].
  ASSERT_TRUE(r.has_home);
  const std::vector<real> home = {0, 0, 0.42f, 0, 0, 0, 1, 0.1f, 0.8f, -1.5f, -0.1f, 0.8f, -1.5f, 0.1f, 1, -1.5f, -0.1f, 1, -1.5f};
  ASSERT_EQ(r.home_q.size(), home.size());
  for (std::size_t k = 0; k < home.size(); ++k) EXPECT_NEAR(r.home_q[k], home[k], 1e-6) << k;
}

TEST(SimArticulatedRobot, AnymalCFromMjcf) {
  const ArticulatedRobot r = load(kAnymalXml);
  EXPECT_EQ(r.name, "anymal_c");
  expect_quadruped(r, 52.13485);  // the sum of anymal_c_simple_description's link masses
  EXPECT_EQ(r.body_names[static_cast<std::size_t>(r.foot_bodies[3])], "RH_FOOT");
  EXPECT_EQ(r.joint_names[static_cast<std::size_t>(find_body(r, "LH_THIGH"))], "LH_HFE");
  for (int i = 1; i < r.multibody.num_bodies; ++i)
    if (r.multibody.joint[i] == dynamics::JointType::revolute) {
      EXPECT_NEAR(r.multibody.effort_limit[i], 80, 1e-5);
      EXPECT_EQ(r.multibody.armature[i], 0);
      EXPECT_NEAR(r.multibody.damping[i], 1, 1e-6);        // Menagerie's ANYdrive D gain
      EXPECT_NEAR(r.multibody.friction_loss[i], 0.1, 1e-6);  // and torque resolution
    }
  const int haa = find_body(r, "RF_HIP");
  EXPECT_NEAR(r.multibody.q_min[haa], -0.49, 1e-6);
  EXPECT_NEAR(r.multibody.q_max[haa], 0.72, 1e-6);
  ASSERT_TRUE(r.has_home);
  const std::vector<real> legs = {0, 0.4f, -0.8f, 0, 0.4f, -0.8f, 0, -0.4f, 0.8f, 0, -0.4f, 0.8f};
  EXPECT_NEAR(r.home_q[2], 0.6, 1e-6);
  EXPECT_NEAR(r.home_q[6], 1, 1e-7);
  for (std::size_t k = 0; k < legs.size(); ++k) EXPECT_NEAR(r.home_q[7 + k], legs[k], 1e-6) << k;
}

TEST(SimArticulatedRobot, So101FromMjcf) {
  const ArticulatedRobot r = load(kSo101Xml);
  EXPECT_EQ(r.name, "so101");
  // The base is welded to the world: its box is a world geom, the shoulder hangs from the world.
  ASSERT_EQ(r.multibody.num_bodies, 7);  // shoulder .. gripper, gripper_frame, moving_jaw
  EXPECT_EQ(r.multibody.num_dofs, 6);
  EXPECT_EQ(r.multibody.num_q, 6);
  const std::vector<std::string> bodies = {"shoulder", "upper_arm",     "lower_arm", "wrist",
                                           "gripper",  "gripper_frame", "moving_jaw"};
  const std::vector<std::string> joints = {"shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex",
                                           "wrist_roll",   "",              "gripper"};
  EXPECT_EQ(r.body_names, bodies);
  EXPECT_EQ(r.joint_names, joints);
  EXPECT_EQ(r.multibody.parent[0], -1);
  EXPECT_NEAR(r.multibody.X_tree[0].r[0], 0.0388353, 1e-7);
  EXPECT_NEAR(r.multibody.X_tree[0].r[2], 0.0624, 1e-7);
  const int frame = find_body(r, "gripper_frame"), gripper = find_body(r, "gripper"), jaw = find_body(r, "moving_jaw");
  ASSERT_EQ(frame, 5);
  EXPECT_EQ(r.multibody.joint[frame], dynamics::JointType::fixed);
  EXPECT_EQ(r.multibody.parent[frame], gripper);
  EXPECT_EQ(r.multibody.parent[jaw], gripper);
  // Menagerie's ranges, and its STS3215: force range 2.94 N m, armature, damping, frictionloss.
  const double lo[] = {-1.91986, -1.7453293, -1.69, -1.658063, -2.7438473, -0.174533};
  const double hi[] = {1.91986, 1.7453293, 1.69, 1.658063, 2.7438473, 1.7453292};
  int k = 0;
  for (int i = 0; i < r.multibody.num_bodies; ++i) {
    if (r.multibody.joint[i] != dynamics::JointType::revolute) continue;
    EXPECT_EQ(r.multibody.dof_index[i], k) << i;
    EXPECT_TRUE(r.multibody.has_limit[i]) << i;
    EXPECT_NEAR(r.multibody.q_min[i], lo[k], 1e-6) << i;
    EXPECT_NEAR(r.multibody.q_max[i], hi[k], 1e-6) << i;
    EXPECT_NEAR(r.multibody.effort_limit[i], 2.94, 1e-6) << i;
    EXPECT_NEAR(r.multibody.armature[i], 0.028, 1e-8) << i;
    EXPECT_NEAR(r.multibody.damping[i], 0.60, 1e-7) << i;
    EXPECT_NEAR(r.multibody.friction_loss[i], 0.052, 1e-8) << i;
    ++k;
  }
  EXPECT_EQ(k, 6);
  // Menagerie's link masses (the base's 0.147 kg is the world's) and gripper_frame's 0.1 g.
  EXPECT_NEAR(r.total_mass_kg, 0.100006 + 0.103 + 0.104 + 0.079 + 0.087 + 0.0001 + 0.012, 1e-6);
  EXPECT_NEAR(r.multibody.body[1].mass, 0.103, 1e-8);
  EXPECT_NEAR(r.multibody.body[1].com[0], -0.089847, 1e-7);
  EXPECT_TRUE(r.foot_bodies.empty());
  // Geoms: the base's box in the world; the pads on the gripper and the moving jaw, 20 x 15 x 4 mm, friction 1.
  const RobotGeom* base = find_geom(r, "base");
  ASSERT_NE(base, nullptr);
  EXPECT_EQ(base->body, -1);
  const RobotGeom* fixed = find_geom(r, "fixed_jaw_pad");
  const RobotGeom* moving = find_geom(r, "moving_jaw_pad");
  ASSERT_NE(fixed, nullptr);
  ASSERT_NE(moving, nullptr);
  EXPECT_EQ(fixed->body, gripper);
  EXPECT_EQ(moving->body, jaw);
  for (const RobotGeom* pad : {fixed, moving}) {
    EXPECT_EQ(pad->type, RobotGeomType::box);
    EXPECT_NEAR(pad->size[0], 0.002, 1e-7);
    EXPECT_NEAR(pad->size[1], 0.0075, 1e-7);
    EXPECT_NEAR(pad->size[2], 0.01, 1e-7);
    EXPECT_NEAR(pad->friction, 1, 1e-7);
  }
  for (const RobotGeom& g : r.geoms) EXPECT_NE(g.type, RobotGeomType::plane) << g.name;  // the task adds the table
  // Home: the keyframe, and gripper_frame's position there as MuJoCo 3.17 computes it from the same
  // file (mj_resetDataKeyframe(m, d, home), mj_forward, d.xpos[gripper_frame]: 0.20160726,
  // -0.00050382, 0.08921751): in front of the base, 9 cm above the table.
  ASSERT_TRUE(r.has_home);
  const std::vector<real> home = {0, -0.35f, 0.35f, 1.55f, 0, 0};
  ASSERT_EQ(r.home_q.size(), home.size());
  for (std::size_t j = 0; j < home.size(); ++j) EXPECT_NEAR(r.home_q[j], home[j], 1e-7) << j;
  dynamics::MultibodyData<kMaxRobotBodies> d;
  dynamics::Transform X_world[kMaxRobotBodies];
  dynamics::forward_kinematics(r.multibody, d, r.home_q.data(), X_world);
  EXPECT_NEAR(X_world[frame].r[0], 0.20160726, 2e-6);
  EXPECT_NEAR(X_world[frame].r[1], -0.00050382, 2e-6);
  EXPECT_NEAR(X_world[frame].r[2], 0.08921751, 2e-6);
  EXPECT_GT(X_world[frame].E(2, 2), 0.9997);  // its z (the gripper's, opposite the fingers) up
  // The pads: overlapping at the closed limit, flat and parallel 25 mm apart at gripper = 0.2 rad
  // (round a 2.5 cm cube), about 8 cm apart at the open limit. The numbers are MuJoCo 3.17's for
  // the same corners (mj_kinematics, geom_xpos / geom_xmat).
  std::vector<real> q(6, 0);
  double dot = 0;
  q[5] = real(-0.174533);
  EXPECT_NEAR(pad_gap(r, q), -0.001856, 2e-5);
  q[5] = real(0.2);
  EXPECT_NEAR(pad_gap(r, q, &dot), 0.025, 2e-5);
  EXPECT_NEAR(dot, 1, 1e-6);
  q[5] = real(1.7453292);
  EXPECT_NEAR(pad_gap(r, q), 0.079557, 2e-5);
  EXPECT_GT(pad_gap(r, q), 0.04);
  // gripper_frame halfway between the pads' centres at that parallel opening.
  q[5] = real(0.2);
  dynamics::forward_kinematics(r.multibody, d, q.data(), X_world);
  Mat3 Rf, Rm;
  Vec3 pf, pm;
  geom_pose(*fixed, X_world, Rf, pf);
  geom_pose(*moving, X_world, Rm, pm);
  EXPECT_LT((X_world[frame].r - 0.5f * (pf + pm)).norm(), 1e-6);
  EXPECT_NEAR((pm - pf).norm(), 0.025 + 2 * 0.002, 1e-6);  // centre to centre: the gap and two half-thicknesses
}

TEST(SimArticulatedRobot, Go2UrdfIsTheSameTreeAsItsMjcf) {
  const ArticulatedRobot x = load(kGo2Xml);
  const ArticulatedRobot u = load(kGo2Urdf);
  EXPECT_EQ(u.name, "go2");
  expect_quadruped(u, 15.017);
  ASSERT_EQ(u.body_names, x.body_names);
  ASSERT_EQ(u.joint_names, x.joint_names);
  EXPECT_FALSE(u.has_home);  // URDF has no keyframes
  for (int i = 0; i < x.multibody.num_bodies; ++i) {
    EXPECT_EQ(u.multibody.parent[i], x.multibody.parent[i]);
    EXPECT_EQ(u.multibody.joint[i], x.multibody.joint[i]);
    EXPECT_EQ(u.multibody.has_limit[i], x.multibody.has_limit[i]) << i;
    EXPECT_NEAR(u.multibody.q_min[i], x.multibody.q_min[i], 1e-6) << i;
    EXPECT_NEAR(u.multibody.q_max[i], x.multibody.q_max[i], 1e-6) << i;
    // URDF <limit effort>, read beside MuJoCo 2.2 (which drops it); MJCF: the motors' ctrlrange.
    EXPECT_NEAR(u.multibody.effort_limit[i], x.multibody.effort_limit[i], 1e-5) << i;
    EXPECT_NEAR(u.multibody.damping[i], x.multibody.damping[i], 1e-7) << i;
    EXPECT_NEAR(u.multibody.friction_loss[i], x.multibody.friction_loss[i], 1e-7) << i;
    EXPECT_EQ(u.multibody.armature[i], 0);  // URDF cannot express rotor inertia
  }
  // Same mass matrix at the MJCF's home pose but for the MJCF's armature on the diagonal.
  const std::vector<real> Hx = mass_matrix(x, x.home_q), Hu = mass_matrix(u, x.home_q);
  const int n = x.multibody.num_dofs;
  double worst = 0;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      double hx = Hx[static_cast<std::size_t>(r * n + c)];
      if (r == c && r >= 6) hx -= 0.01;  // go2.xml's armature on every leg joint
      worst = std::max(worst, std::fabs(hx - Hu[static_cast<std::size_t>(r * n + c)]));
    }
  EXPECT_LT(worst, 1e-5);
  // A wrong placement shows: the URDF's tree at another pose is not the MJCF's at home.
  std::vector<real> q2 = x.home_q;
  q2[8] += 0.3f;
  const std::vector<real> H2 = mass_matrix(u, q2);
  double moved = 0;
  for (std::size_t k = 0; k < H2.size(); ++k) moved = std::max(moved, std::fabs(double(H2[k]) - Hu[k]));
  EXPECT_GT(moved, 1e-3);
}

TEST(SimArticulatedRobot, ErrorsNameTheFileAndTheProblem) {
  struct Case {
    const char* file;
    std::string xml;
    const char* what;
  };
  const std::string body = "<inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"0.1 0.1 0.1\"/>";
  const std::vector<Case> cases = {
      {"malformed.xml", "<mujoco><worldbody><body name=\"a\"></worldbody></mujoco>", "Error"},
      {"unknown_element.xml", "<mujoco><worldbody><bodie name=\"a\"/></worldbody></mujoco>", "bodie"},
      {"ball.xml", "<mujoco><worldbody><body name=\"a\">" + body + "<joint name=\"j\" type=\"ball\"/></body></worldbody></mujoco>",
       "joint \"j\": ball joints are not supported"},
      {"two_joints.xml",
       "<mujoco><worldbody><body name=\"a\">" + body +
           "<joint name=\"j1\" axis=\"1 0 0\"/><joint name=\"j2\" axis=\"0 1 0\"/></body></worldbody></mujoco>",
       "body \"a\": 2 joints"},
      {"late_free.xml",
       "<mujoco><worldbody><body name=\"a\">" + body + "<freejoint name=\"f0\"/></body><body name=\"b\">" + body +
           "<freejoint name=\"f\"/></body></worldbody></mujoco>",
       "free joint only on the first body"},
      {"tendon.xml",
       "<mujoco><worldbody><body name=\"a\">" + body +
           "<joint name=\"j\"/></body></worldbody><tendon><fixed name=\"t\"><joint joint=\"j\" coef=\"1\"/></fixed></tendon></mujoco>",
       "tendon: tendons are not supported"},
      {"massless.xml",
       "<mujoco><worldbody><body name=\"a\">" + body + "<joint name=\"j\"/><body name=\"tip\"/></body></worldbody></mujoco>",
       "body \"tip\": mass 0"},
      {"asymmetric.xml",
       "<mujoco><worldbody><body name=\"a\">" + body +
           "<joint name=\"j\"/></body></worldbody><actuator><motor name=\"m\" joint=\"j\" ctrllimited=\"true\" ctrlrange=\"-1 2\"/></actuator></mujoco>",
       "actuator \"m\"@ctrlrange: an asymmetric range"},
  };
  for (const Case& c : cases) {
    const std::string path = write_temp(c.file, c.xml);
    ArticulatedRobot r;
    r.name = "untouched";
    std::string err;
    EXPECT_FALSE(load_robot_model(path, r, err)) << c.file;
    EXPECT_EQ(err.rfind(path + ": ", 0), 0u) << err;  // the file first
    EXPECT_NE(err.find(c.what), std::string::npos) << c.file << ": " << err;
    EXPECT_EQ(r.name, "untouched");  // nothing half-built
    EXPECT_EQ(r.multibody.num_bodies, 0);
    std::printf("%s\n", err.c_str());  // the messages, for the record
  }
  ArticulatedRobot r;
  std::string err;
  EXPECT_FALSE(load_robot_model(kModels + "/no_such_robot.xml", r, err));
  EXPECT_EQ(err, kModels + "/no_such_robot.xml: cannot open file");
}

// A collision mesh comes in as its hull's vertices in the geom's frame (dynamics ShapeType::convex):
// a tetrahedron keeps its 4 corners (MuJoCo recentres a mesh on its centroid and moves the geom
// there), a 200-vertex sphere mesh is cut to kMaxMeshCollisionPoints extreme points on its surface.
TEST(SimArticulatedRobot, CollisionMeshesBecomeTheirHullPoints) {
  const std::string body = "<inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"0.1 0.1 0.1\"/>";
  std::string sphere;
  for (int k = 0; k < 200; ++k) {  // points on a 0.05 m sphere (a Fibonacci lattice)
    const double z = 1 - 2 * (k + 0.5) / 200, r = std::sqrt(1 - z * z), phi = 2.399963229728653 * k;
    sphere += std::to_string(0.05 * r * std::cos(phi)) + " " + std::to_string(0.05 * r * std::sin(phi)) + " " + std::to_string(0.05 * z) + " ";
  }
  const std::string path = write_temp(
      "meshes.xml", "<mujoco><asset><mesh name=\"tet\" vertex=\"0 0 0 0.1 0 0 0 0.1 0 0 0 0.1\"/><mesh name=\"ball\" vertex=\"" +
                        sphere + "\"/></asset><worldbody><body name=\"a\">" + body +
                        "<joint name=\"j\"/><geom name=\"hull\" type=\"mesh\" mesh=\"tet\"/>"
                        "<geom name=\"ball\" type=\"mesh\" mesh=\"ball\" pos=\"0 0 -0.3\"/></body></worldbody></mujoco>");
  const ArticulatedRobot r = load(path);
  ASSERT_EQ(r.geoms.size(), 2u);
  const RobotGeom& tet = r.geoms[0];
  EXPECT_EQ(tet.type, RobotGeomType::mesh);
  ASSERT_EQ(tet.points.size(), 4u);
  // The corners back in the body frame: pos + R p gives {0, 0.1 x, 0.1 y, 0.1 z} in some order.
  const Mat3 R = rotation_matrix(quat_from_xyzw(tet.quat_xyzw_b));
  int matched = 0;
  for (const Vec3& corner : {Vec3(0, 0, 0), Vec3(0.1_r, 0, 0), Vec3(0, 0.1_r, 0), Vec3(0, 0, 0.1_r)})
    for (const Vec3& p : tet.points) matched += ((tet.pos_b + R * p) - corner).norm() < 1e-5 ? 1 : 0;
  EXPECT_EQ(matched, 4);
  dynamics::CollisionShape cs;
  ASSERT_TRUE(to_collision_shape(tet, cs));
  EXPECT_EQ(cs.type, dynamics::ShapeType::convex);
  EXPECT_EQ(cs.points, tet.points.data());
  EXPECT_EQ(cs.num_points, 4);
  const RobotGeom& ball = r.geoms[1];
  EXPECT_EQ(static_cast<int>(ball.points.size()), kMaxMeshCollisionPoints);
  for (const Vec3& p : ball.points) EXPECT_NEAR(p.norm(), 0.05, 2e-3);  // on the surface (hull vertices)
}

TEST(SimArticulatedRobot, JointOffsetMovesTheBodyFrameToTheJoint) {
  // A pendulum whose hinge sits 0.2 m above its body origin (MJCF <joint pos>) is the same
  // dynamics as one written with the body at the hinge: same mass matrix at any angle.
  const std::string inertial = "<inertial pos=\"0 0 -0.3\" mass=\"2\" diaginertia=\"0.01 0.02 0.03\"/>";
  const std::string a = write_temp("offset_a.xml", "<mujoco><worldbody><body name=\"p\" pos=\"0 0 0.8\">" + inertial +
                                                       "<joint name=\"j\" axis=\"0 1 0\" pos=\"0 0 0.2\"/></body></worldbody></mujoco>");
  const std::string b = write_temp("offset_b.xml",
                                   "<mujoco><worldbody><body name=\"p\" pos=\"0 0 1\"><inertial pos=\"0 0 -0.5\" mass=\"2\" "
                                   "diaginertia=\"0.01 0.02 0.03\"/><joint name=\"j\" axis=\"0 1 0\"/></body></worldbody></mujoco>");
  const ArticulatedRobot ra = load(a), rb = load(b);
  for (real q : {0.0f, 0.7f, -2.0f}) {
    const std::vector<real> qa = {q};
    EXPECT_NEAR(mass_matrix(ra, qa)[0], mass_matrix(rb, qa)[0], 1e-6);
    EXPECT_NEAR(mass_matrix(ra, qa)[0], 0.02 + 2 * 0.25, 1e-5);  // I_yy + m d^2
  }
  EXPECT_NEAR(ra.multibody.X_tree[0].r[2], 1.0, 1e-6);
  EXPECT_NEAR(ra.multibody.body[0].com[2], -0.5, 1e-6);
}

TEST(SimArticulatedRobot, BodiesWeldedToTheWorldArePartOfIt) {
  // A floor plane and a static box body in the world, then a hinged arm under the static body: the
  // arm is body 0 (from the world, at the static body's pose), the plane and the box are world
  // geoms (body -1) at their world poses, and a visual-only geom is left out.
  const std::string path = write_temp(
      "welded.xml",
      "<mujoco><worldbody><geom name=\"floor\" type=\"plane\" size=\"5 5 0.1\"/>"
      "<body name=\"stand\" pos=\"1 0 0.5\" quat=\"0.7071068 0 0 0.7071068\"><geom name=\"post\" type=\"box\" size=\"0.1 0.1 0.5\" pos=\"0 0 -0.25\"/>"
      "<body name=\"arm\" pos=\"0.2 0 0\"><inertial pos=\"0.3 0 0\" mass=\"1\" diaginertia=\"0.01 0.02 0.02\"/>"
      "<joint name=\"shoulder\" axis=\"0 1 0\"/><geom type=\"capsule\" fromto=\"0 0 0 0.6 0 0\" size=\"0.05\" mass=\"0\"/>"
      "<geom type=\"sphere\" size=\"0.2\" contype=\"0\" conaffinity=\"0\" mass=\"0\"/></body></body></worldbody></mujoco>");
  const ArticulatedRobot r = load(path);
  ASSERT_EQ(r.multibody.num_bodies, 1);
  EXPECT_EQ(r.body_names[0], "arm");
  EXPECT_EQ(r.multibody.parent[0], -1);
  EXPECT_EQ(r.multibody.num_dofs, 1);
  // Placed at the stand's pose: (1, 0, 0.5) + Rz(90 deg) (0.2, 0, 0) = (1, 0.2, 0.5).
  EXPECT_NEAR(r.multibody.X_tree[0].r[0], 1.0, 1e-6);
  EXPECT_NEAR(r.multibody.X_tree[0].r[1], 0.2, 1e-6);
  EXPECT_NEAR(r.multibody.X_tree[0].r[2], 0.5, 1e-6);
  EXPECT_NEAR(r.multibody.X_tree[0].E(0, 1), 1.0, 1e-6);  // E = Rz(90 deg)^T
  ASSERT_EQ(r.geoms.size(), 3u);  // floor, post, the arm's capsule (the sphere is visual only)
  EXPECT_EQ(r.geoms[0].name, "floor");
  EXPECT_EQ(r.geoms[0].type, RobotGeomType::plane);
  EXPECT_EQ(r.geoms[0].body, -1);
  EXPECT_EQ(r.geoms[1].name, "post");
  EXPECT_EQ(r.geoms[1].body, -1);
  EXPECT_NEAR(r.geoms[1].pos_b[2], 0.25, 1e-6);  // 0.5 - 0.25, in the world
  EXPECT_EQ(r.geoms[2].type, RobotGeomType::capsule);
  EXPECT_EQ(r.geoms[2].body, 0);
  EXPECT_TRUE(r.foot_bodies.empty());
  EXPECT_FALSE(r.has_home);
}
