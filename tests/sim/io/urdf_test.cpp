// URDF robot input (sim/urdf.hpp): parsed values equal the file's (composite mass and inertia by
// hand), rotor geometry into the airframe, the scenario's `robot: {urdf: ...}`, and errors that
// name the file and the element.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/urdf.hpp"
#include "kestrel/sim/world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {
const std::string kQuad = std::string(KESTREL_SIM_TEST_DIR) + "/data/quad.urdf";

std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = std::string(::testing::TempDir()) + "/" + name;
  std::ofstream(path) << text;
  return path;
}
// A one-link robot around `body` (the inner XML of base_link) plus `extra` elements.
std::string robot_xml(const std::string& body, const std::string& extra = "") {
  return "<?xml version=\"1.0\"?>\n<robot name=\"t\">\n<link name=\"base_link\">" + body + "</link>\n" + extra + "</robot>\n";
}
const char* kInertial = "<inertial><mass value=\"1\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.2\" iyz=\"0\" izz=\"0.3\"/></inertial>";
std::string rotor(int n, const char* joint_type, const char* axis, const char* xyz = "0.1 0 0") {
  return "<link name=\"rotor_" + std::to_string(n) + "\"/><joint name=\"j" + std::to_string(n) + "\" type=\"" + joint_type +
         "\"><parent link=\"base_link\"/><child link=\"rotor_" + std::to_string(n) + "\"/><origin xyz=\"" + xyz +
         "\"/>" + (axis ? std::string("<axis xyz=\"") + axis + "\"/>" : std::string()) + "</joint>\n";
}
void expect_error(const std::string& file, const std::string& xml, const std::string& what) {
  const std::string path = write_temp(file, xml);
  UrdfRobot u;
  std::string err;
  EXPECT_FALSE(load_urdf(path, u, err)) << file;
  EXPECT_NE(err.find(path + ": "), std::string::npos) << err;  // the file
  EXPECT_NE(err.find(what), std::string::npos) << err;          // the element and what is allowed
}
}  // namespace

TEST(SimUrdf, SampleQuadValuesEqualTheFile) {
  UrdfRobot u;
  std::string err;
  ASSERT_TRUE(load_urdf(kQuad, u, err)) << err;
  EXPECT_EQ(u.name, "sample_quad");
  EXPECT_EQ(u.base_link, "base_link");
  // 0.2 kg base + 4 x 0.0125 kg props; composite inertia about the centre of mass (the base
  // origin): base 1e-3 + 0.2 * 0.005^2 (its 5 mm offset), props 1e-6 + m (y^2 + z^2) each, etc.
  EXPECT_NEAR(u.mass_kg, 0.25, 1e-7);
  EXPECT_NEAR(u.inertia_diag_kg_m2[0], 1e-3 + 0.2 * 2.5e-5 + 4 * (1e-6 + 0.0125 * (0.0169 + 0.0004)), 1e-9);
  EXPECT_NEAR(u.inertia_diag_kg_m2[1], 1e-3 + 0.2 * 2.5e-5 + 4 * (1e-6 + 0.0125 * (0.0169 + 0.0004)), 1e-9);
  EXPECT_NEAR(u.inertia_diag_kg_m2[2], 2e-3 + 4 * (2e-6 + 0.0125 * 0.0338), 1e-9);
  ASSERT_TRUE(u.has_shape);
  EXPECT_EQ(u.shape.type, ShapeType::box);
  EXPECT_NEAR(u.shape.half_extents_m[0], 0.15, 1e-7);
  EXPECT_NEAR(u.shape.half_extents_m[2], 0.05, 1e-7);
  ASSERT_EQ(u.rotors.size(), 4u);
  const real px[4] = {0.13_r, -0.13_r, -0.13_r, 0.13_r}, py[4] = {-0.13_r, -0.13_r, 0.13_r, 0.13_r};
  const int dir[4] = {1, -1, 1, -1};
  for (int m = 0; m < 4; ++m) {
    EXPECT_NEAR(u.rotors[m].position_b_m[0], px[m], 1e-7) << m;  // prop_0 through the arm link's chain
    EXPECT_NEAR(u.rotors[m].position_b_m[1], py[m], 1e-7) << m;
    EXPECT_NEAR(u.rotors[m].position_b_m[2], 0.02, 1e-7) << m;
    EXPECT_NEAR(u.rotors[m].axis_b[2], 1, 1e-7) << m;
    EXPECT_EQ(u.rotor_directions[m], dir[m]) << m;
  }
}

TEST(SimUrdf, TiltedRotorAxisAndJointRotationsCompose) {
  // rotor_0 on a joint rolled by +90 deg about x: its +z (thrust) axis points along -y.
  const std::string xml = robot_xml(kInertial, "<link name=\"rotor_0\"/><joint name=\"j0\" type=\"continuous\"><parent link=\"base_link\"/>"
                                               "<child link=\"rotor_0\"/><origin xyz=\"0 0.2 0\" rpy=\"1.5707963267948966 0 0\"/>"
                                               "<axis xyz=\"0 0 -1\"/></joint>\n");
  UrdfRobot u;
  std::string err;
  ASSERT_TRUE(load_urdf(write_temp("tilted.urdf", xml), u, err)) << err;
  ASSERT_EQ(u.rotors.size(), 1u);
  EXPECT_NEAR(u.rotors[0].axis_b[1], -1, 1e-6);
  EXPECT_NEAR(u.rotors[0].axis_b[2], 0, 1e-6);
  EXPECT_NEAR(u.rotors[0].position_b_m[1], 0.2, 1e-7);
  EXPECT_EQ(u.rotor_directions[0], -1);
  EXPECT_FALSE(u.has_shape);  // no <collision>: the configured shape stays
}

TEST(SimUrdf, ScenarioRobotFromUrdfBuildsTheAirframeAndHovers) {
  WorldConfig c;
  std::string err;
  ASSERT_TRUE(load_scenario_string("env: {name: empty, num_envs: 4}\nrobot: {name: base_quadrotor, urdf: " + kQuad +
                                       ", quadratic_drag_b: [0.01, 0.01, 0.01]}\ntask: hover\n",
                                   "u.yaml", c, err))
      << err;
  EXPECT_NEAR(c.robot.mass_kg, 0.25, 1e-7);
  EXPECT_EQ(c.robot.shape.type, ShapeType::box);
  EXPECT_EQ(c.robot.rotors.size(), 4u);
  EXPECT_NEAR(c.robot.quadratic_drag_b[0], 0.01, 1e-7);  // the section's own fields still apply
  auto w = World::create(c, err);
  ASSERT_TRUE(w) << err;
  // Column 0 of A = rotor 0's wrench per newton: force +z, torque r x z + reaction -dir * ratio * z.
  const auto& A = w->airframe().effectiveness;
  EXPECT_NEAR(A(2, 0), 1, 1e-6);
  EXPECT_NEAR(A(3, 0), -0.13, 1e-6);  // tau_x = y * fz
  EXPECT_NEAR(A(4, 0), -0.13, 1e-6);  // tau_y = -x * fz
  EXPECT_NEAR(A(5, 0), -0.01, 1e-6);  // direction +1, ratio 0.01
  EXPECT_NEAR(A(5, 1), 0.01, 1e-6);
  w->step(300);
  EXPECT_EQ(w->summary().crashes, 0u);
  EXPECT_LT(w->summary().final_mean_distance_m, 0.05);
  // Errors from the URDF name the scenario field and the file.
  ASSERT_FALSE(load_scenario_string("robot: {name: base_quadrotor, urdf: nope.urdf}\n", "u.yaml", c, err));
  EXPECT_NE(err.find("u.yaml: robot.urdf: nope.urdf: cannot open file"), std::string::npos) << err;
}

TEST(SimUrdf, BadInputErrorsNameFileAndElement) {
  expect_error("notxml.urdf", "<robot><link name=\"a\"></robot>", "not well-formed XML");
  expect_error("noroot.urdf", "<model/>", "robot: missing the <robot> root element");
  expect_error("nomass.urdf", robot_xml("<inertial><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial>"),
               "link[base_link]/inertial/mass: missing");
  expect_error("badmass.urdf", robot_xml("<inertial><mass value=\"heavy\"/></inertial>"),
               "link[base_link]/inertial/mass@value: expected a finite number, got \"heavy\"");
  expect_error("massless.urdf", robot_xml(""), "link[base_link]/inertial/mass: the robot has no mass");
  expect_error("products.urdf",
               robot_xml("<inertial><mass value=\"1\"/><inertia ixx=\"1\" ixy=\"0.2\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial>"),
               "link[base_link]/inertial/inertia: products of inertia");
  expect_error("mesh.urdf",
               robot_xml(std::string(kInertial) + "<collision><geometry><mesh filename=\"q.stl\"/></geometry></collision>"),
               "link[base_link]/collision/geometry/mesh: unsupported geometry; allowed: box, sphere, cylinder");
  expect_error("box.urdf", robot_xml(std::string(kInertial) + "<collision><geometry><box size=\"1 2\"/></geometry></collision>"),
               "link[base_link]/collision/geometry/box@size: expected three finite numbers");
  expect_error("colorigin.urdf",
               robot_xml(std::string(kInertial) + "<collision><origin xyz=\"0 0 0.1\"/><geometry><sphere radius=\"0.1\"/></geometry></collision>"),
               "link[base_link]/collision/origin: expected a zero origin");
  expect_error("gap.urdf", robot_xml(kInertial, rotor(0, "continuous", "0 0 1") + rotor(2, "continuous", "0 0 1")),
               "link[rotor_2]: rotor links must be numbered 0, 1, ... without gaps (missing rotor_1)");
  expect_error("fixed.urdf", robot_xml(kInertial, rotor(0, "fixed", nullptr)),
               "joint[j0]@type: a rotor's joint must be continuous or revolute");
  expect_error("axis.urdf", robot_xml(kInertial, rotor(0, "continuous", "1 0 0")), "joint[j0]/axis@xyz: expected 0 0 1 or 0 0 -1");
  expect_error("unknown.urdf",
               robot_xml(kInertial, "<joint name=\"j\" type=\"fixed\"><parent link=\"base_link\"/><child link=\"ghost\"/></joint>"),
               "joint[j]/child@link: unknown link \"ghost\"");
  expect_error("tworoots.urdf", robot_xml(kInertial, "<link name=\"other\"/>"), "robot: two root links");
  UrdfRobot u;
  std::string err;
  EXPECT_FALSE(load_urdf("/nonexistent/x.urdf", u, err));
  EXPECT_EQ(err, "/nonexistent/x.urdf: cannot open file");
}
