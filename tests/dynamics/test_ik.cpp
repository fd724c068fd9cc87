// Inverse kinematics by damped least squares (dynamics/ik.hpp), on the host and the emulated MCU:
// a 4-joint spatial arm reaches targets that a known configuration puts its tool at, to 0.1 mm,
// with and without the tool's orientation; a target out of reach ends stretched towards it,
// within the joint limits; refusals leave q alone.
#include <cmath>

#include "kestrel/dynamics/ik.hpp"
#include "kestrel/kernel/rng.hpp"
#include "ktest.hpp"

using namespace kestrel;
namespace dy = kestrel::dynamics;

namespace {

// A pan joint about z, then three pitch joints about y along 0.12 m links (an arm like the
// SO-101's first four joints); the tool point 0.1 m beyond the last.
void arm(dy::MultibodyModel<4>& m) {
  m.num_bodies = 4;
  for (int i = 0; i < 4; ++i) {
    m.parent[i] = i - 1;
    m.joint[i] = dy::JointType::revolute;
    m.axis[i] = i == 0 ? Vec3(0, 0, 1) : Vec3(0, 1, 0);
    m.X_tree[i].r = i == 0 ? Vec3(0, 0, 0.05_r) : (i == 1 ? Vec3(0, 0, 0.03_r) : Vec3(0.12_r, 0, 0));
    m.body[i].mass = 0.1_r;
    m.body[i].inertia_com = Vec3::Constant(1e-4_r).asDiagonal();
    m.has_limit[i] = true;
    m.q_min[i] = -2;
    m.q_max[i] = 2;
  }
  KASSERT_EQ(dy::finish_model(m), Status::ok);
}

void tool_pose(const dy::MultibodyModel<4>& m, dy::MultibodyData<4>& d, const real* q, Vec3& p_w, Mat3& R_w) {
  dy::Transform X[4];
  dy::forward_kinematics(m, d, q, X);
  R_w = X[3].E.transpose();
  p_w = X[3].r + R_w * Vec3(0.1_r, 0, 0);
}

}  // namespace

KTEST(Ik, ReachesPosesAKnownConfigurationGives) {
  static dy::MultibodyModel<4> m;
  static dy::MultibodyData<4> d;
  arm(m);
  RngStream rng(7, 0, 0);
  const Vec3 tool_b(0.1_r, 0, 0);
  int reached = 0, reached_pose = 0;
  for (int trial = 0; trial < 50; ++trial) {
    real goal[4], q[4] = {0, 0.3_r, 0.6_r, 0.3_r};
    for (real& g : goal) g = rng.uniform(-1.2_r, 1.2_r);
    Vec3 p;
    Mat3 R;
    tool_pose(m, d, goal, p, R);
    dy::IkParams prm;
    prm.iterations = 100;
    dy::IkResult res;
    KASSERT_EQ(dy::solve_ik(m, d, q, 3, tool_b, p, nullptr, prm, res), Status::ok);
    Vec3 p2;
    Mat3 R2;
    tool_pose(m, d, q, p2, R2);
    KEXPECT_CLOSE(res.position_error_m, (p2 - p).norm(), 1e-6, 0, "reported error");
    if ((p2 - p).norm() < real(1e-4)) ++reached;
    for (int i = 0; i < 4; ++i) KEXPECT_TRUE(q[i] >= -2 && q[i] <= 2);
    // With the orientation too (4 joints: the pitch sum and the pan are reachable from the goal).
    real q2[4] = {0, 0.3_r, 0.6_r, 0.3_r};
    prm.orientation_weight = 0.1_r;
    KASSERT_EQ(dy::solve_ik(m, d, q2, 3, tool_b, p, &R, prm, res), Status::ok);
    tool_pose(m, d, q2, p2, R2);
    const Eigen::AngleAxis<real> err(R2 * R.transpose());
    if ((p2 - p).norm() < real(1e-3) && std::fabs(err.angle()) < real(0.01)) ++reached_pose;
  }
  // Damped steps from one start: a few goals behind a limit or across a singularity end elsewhere.
  KEXPECT_GE(reached, 45);
  KEXPECT_GE(reached_pose, 45);
}

KTEST(Ik, OutOfReachStretchesTowardsTheTarget) {
  static dy::MultibodyModel<4> m;
  static dy::MultibodyData<4> d;
  arm(m);
  real q[4] = {0, 0.3_r, 0.6_r, 0.3_r};
  dy::IkParams prm;
  prm.iterations = 200;
  dy::IkResult res;
  const Vec3 far(1, 0, 0.08_r);  // reach is 0.12 + 0.12 + 0.1 = 0.34 m from the shoulder
  KASSERT_EQ(dy::solve_ik(m, d, q, 3, Vec3(0.1_r, 0, 0), far, nullptr, prm, res), Status::ok);
  KEXPECT_CLOSE(res.position_error_m, 1 - 0.34, 5e-3, 0, "distance left (m)");
  for (real qi : q) KEXPECT_TRUE(std::isfinite(qi) && qi >= -2 && qi <= 2);
  // Refusals leave q alone.
  real q0[4] = {0.1_r, 0.2_r, 0.3_r, 0.4_r};
  KEXPECT_EQ(dy::solve_ik(m, d, q0, 7, Vec3::Zero(), far, nullptr, prm, res), Status::invalid_argument);
  KEXPECT_EQ(dy::solve_ik(m, d, q0, 3, Vec3::Zero(), Vec3(NAN, 0, 0), nullptr, prm, res), Status::invalid_argument);
  KEXPECT_EQ(q0[0], 0.1_r);
  q0[2] = NAN;
  KEXPECT_EQ(dy::solve_ik(m, d, q0, 3, Vec3::Zero(), far, nullptr, prm, res), Status::non_finite_input);
}
