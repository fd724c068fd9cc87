// Robot files into the core's articulated-body model (sim/articulated_robot.hpp): the shipped Go2
// and ANYmal C (models/), their counts, masses, feet, home pose and limits as the files give them;
// the Go2 as MJCF and as URDF giving the same tree (same mass matrix); and errors that name the
// file and the problem, leaving the output untouched.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "kestrel/sim/articulated_robot.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {
const std::string kModels = std::string(KESTREL_SIM_TEST_DIR) + "/../../models";
const std::string kGo2Xml = kModels + "/go2/go2.xml";
const std::string kGo2Urdf = kModels + "/go2/go2.urdf";
const std::string kAnymalXml = kModels + "/anymal_c/anymal_c.xml";

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
      {"mesh.xml",
       "<mujoco><asset><mesh name=\"tet\" vertex=\"0 0 0 0.1 0 0 0 0.1 0 0 0 0.1\"/></asset><worldbody><body name=\"a\">" +
           body + "<joint name=\"j\"/><geom name=\"hull\" type=\"mesh\" mesh=\"tet\"/></body></worldbody></mujoco>",
       "geom \"hull\" (in body \"a\"): mesh collision is not supported"},
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
