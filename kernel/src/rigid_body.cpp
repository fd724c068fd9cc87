#include "kestrel/kernel/rigid_body.hpp"

#include <cmath>

#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"

namespace kestrel {

Status make_rigid_body_model(const RigidBodyParams& params, RigidBodyModel& out) {
  if (!(params.mass_kg > 0) || !is_finite(params.mass_kg)) return Status::invalid_argument;
  if (!all_finite(params.inertia_b) || !all_finite(params.gravity_w)) return Status::invalid_argument;
  const Mat3& j = params.inertia_b;
  // Symmetric positive definite: Sylvester's criterion on the leading minors.
  if (!((j - j.transpose()).cwiseAbs().maxCoeff() <= 1e-6_r * j.cwiseAbs().maxCoeff())) return Status::invalid_argument;
  const real m1 = j(0, 0);
  const real m2 = j(0, 0) * j(1, 1) - j(0, 1) * j(1, 0);
  const real m3 = j.determinant();
  if (!(m1 > 0 && m2 > 0 && m3 > 0)) return Status::invalid_argument;
  out.params = params;
  out.inv_inertia_b = j.inverse();
  out.inv_mass = 1 / params.mass_kg;
  return Status::ok;
}

namespace {

struct Deriv {
  Vec3 dp;
  Vec4 dq;  // xyzw derivative
  Vec3 dv;
  Vec3 dw;
};

inline Vec3 drag_force_b(const RigidBodyParams& p, const Vec3& v_b) {
  return -(p.linear_drag_b.cwiseProduct(v_b) + p.quadratic_drag_b.cwiseProduct(v_b.cwiseAbs().cwiseProduct(v_b)));
}
inline Vec3 drag_torque_b(const RigidBodyParams& p, const Vec3& w_b) {
  return -(p.angular_drag_b.cwiseProduct(w_b) +
           p.quadratic_angular_drag_b.cwiseProduct(w_b.cwiseAbs().cwiseProduct(w_b)));
}

RigidBodyAccel accel(const RigidBodyModel& m, const Quat& q, const Vec3& v_w, const Vec3& w_b, const Wrench& wr,
                     const Vec3& extra_w) {
  const RigidBodyParams& p = m.params;
  const Vec3 v_b = rotate_inverse(q, v_w);
  const Vec3 f_b = wr.force_b + drag_force_b(p, v_b);
  RigidBodyAccel a;
  a.linacc_w = rotate(q, f_b) * m.inv_mass + p.gravity_w + extra_w * m.inv_mass;
  const Vec3 tau = wr.torque_b + drag_torque_b(p, w_b) - w_b.cross(p.inertia_b * w_b);
  a.angacc_b = m.inv_inertia_b * tau;
  return a;
}

inline Vec4 quat_deriv(const Quat& q, const Vec3& w_b) {
  // dq/dt = 1/2 q (x) (w_b, 0)
  const Quat omega = quat_from_xyzw(w_b[0], w_b[1], w_b[2], 0);
  const Quat d = quat_mul(q, omega);  // not q * omega: the same bits on host and MCU
  return to_xyzw(d) * 0.5_r;
}

Deriv deriv(const RigidBodyModel& m, const Vec3& /*p*/, const Quat& q, const Vec3& v, const Vec3& w, const Wrench& wr,
            const Vec3& extra) {
  const RigidBodyAccel a = accel(m, q, v, w, wr, extra);
  return Deriv{v, quat_deriv(q, w), a.linacc_w, a.angacc_b};
}

inline Quat normalized_or_identity(const Vec4& xyzw) {
  const real n = norm_xyzw(xyzw);  // not xyzw.norm(): the same bits on host and MCU
  if (!(n > 0) || !is_finite(n)) return Quat::Identity();
  return quat_from_xyzw(xyzw / n);
}

}  // namespace

RigidBodyAccel rigid_body_accel(const RigidBodyModel& model, const RigidBodyState& s, const Wrench& wrench) {
  return accel(model, s.orientation_wb, s.linvel_w, s.angvel_b, wrench, Vec3::Zero());
}

Status step_rigid_body(const RigidBodyModel& model, RigidBodyState& s, const Wrench& wr, real dt,
                       const Vec3& extra_w) {
  if (!all_finite(wr.force_b) || !all_finite(wr.torque_b) || !all_finite(extra_w) || !is_finite(dt) || !(dt >= 0)) {
    return Status::non_finite_input;
  }
  RigidBodyState n = s;
  if (model.params.integrator == Integrator::semi_implicit_euler) {
    const RigidBodyAccel a = accel(model, s.orientation_wb, s.linvel_w, s.angvel_b, wr, extra_w);
    n.linvel_w = s.linvel_w + a.linacc_w * dt;
    n.angvel_b = s.angvel_b + a.angacc_b * dt;
    n.position_w = s.position_w + n.linvel_w * dt;
    // Exact attitude update for constant body rate over the step: q <- q (x) exp(w dt / 2).
    const real angle = n.angvel_b.norm() * dt;
    Quat dq = Quat::Identity();
    if (angle > 0) {
      const Vec3 axis = n.angvel_b.normalized();
      const real h = angle * 0.5_r;
      // The core's sin_cos (kernel/math.hpp: Cephes' polynomial in float, no libm), not std::sin /
      // std::cos: the same bits on the host and every MCU, and the batched step computes it in
      // its lanes instead of calling libm once per robot.
      real sh = 0, ch = 1;
      sin_cos(h, sh, ch);
      dq = quat_from_xyzw(axis[0] * sh, axis[1] * sh, axis[2] * sh, ch);
    }
    n.orientation_wb = normalized_or_identity(to_xyzw(quat_mul(s.orientation_wb, dq)));
  } else {
    const Vec3 p0 = s.position_w, v0 = s.linvel_w, w0 = s.angvel_b;
    const Vec4 q0 = to_xyzw(s.orientation_wb);
    auto q_at = [&](const Vec4& dq, real h) { return normalized_or_identity(q0 + dq * h); };
    const Deriv k1 = deriv(model, p0, s.orientation_wb, v0, w0, wr, extra_w);
    const real h2 = dt * 0.5_r;
    const Deriv k2 = deriv(model, p0 + k1.dp * h2, q_at(k1.dq, h2), v0 + k1.dv * h2, w0 + k1.dw * h2, wr, extra_w);
    const Deriv k3 = deriv(model, p0 + k2.dp * h2, q_at(k2.dq, h2), v0 + k2.dv * h2, w0 + k2.dw * h2, wr, extra_w);
    const Deriv k4 = deriv(model, p0 + k3.dp * dt, q_at(k3.dq, dt), v0 + k3.dv * dt, w0 + k3.dw * dt, wr, extra_w);
    const real s6 = dt / 6;
    n.position_w = p0 + (k1.dp + 2 * k2.dp + 2 * k3.dp + k4.dp) * s6;
    n.linvel_w = v0 + (k1.dv + 2 * k2.dv + 2 * k3.dv + k4.dv) * s6;
    n.angvel_b = w0 + (k1.dw + 2 * k2.dw + 2 * k3.dw + k4.dw) * s6;
    n.orientation_wb = normalized_or_identity(q0 + (k1.dq + 2 * k2.dq + 2 * k3.dq + k4.dq) * s6);
  }
  if (!all_finite(n.position_w) || !all_finite(n.linvel_w) || !all_finite(n.angvel_b)) {
    return Status::non_finite_input;  // state overflowed (absurd wrench): keep the last good state
  }
  s = n;
  return Status::ok;
}

}  // namespace kestrel
