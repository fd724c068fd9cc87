// Golden parity: every case of every controller in golden/controllers.json (produced by running
// Aerial Gym's own controller code), within the file's recommended float32 tolerances.
//
// The file is streamed with the heap-free pull reader; one controller entry at a time is kept in
// the shared test scratch (keys arrive in file order: params, status, cases, and for lee_rates
// partial_torque_only after the cases), then checked through the dispatch table. Inputs are parsed
// as float32 (the reference's exact values) and widened to `real`. Counts come from the file (any
// number of cases, up to kMaxCases per controller); tolerances from its conventions.
#include <cmath>
#include <cstring>

#include "golden_tol.hpp"
#include "json_pull.hpp"
#include "kestrel/controllers/controller.hpp"
#include "kestrel/kernel/math.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "ktest.hpp"
#include "test_io.hpp"
#include "test_scratch.hpp"

using namespace kestrel;

namespace {

constexpr int kMaxCases = 64;

using Tol = ktest::GoldenTol;

struct Tolerances {
  Tol force;
  Tol torque;
  Tol inter;
};

struct GoldenCase {
  float pos[3];
  float quat[4];
  float linvel[3];
  float body_angvel[3];
  float euler[3];
  float vehicle_quat[4];
  float vehicle_linvel[3];
  float action_raw[7];
  float command[7];
  int action_len;
  int command_len;
  float wrench[6];
  bool has_wrench;
  float accel[3];
  bool has_accel;
  float quat_d[4];
  bool has_quat_d;
  float w_d[3];
  bool has_w_d;
  float cmd_after_norm[7];
  bool has_cmd_after_norm;
};

struct GoldenController {
  char robot[32];
  char status[16];
  float mass;
  float inertia[9];
  float gravity[3];
  float max_yaw_rate;
  float k_pos[3], k_vel[3], k_rot[3], k_angvel[3];
  float action_clip[2];
  int num_cases;
  GoldenCase cases[kMaxCases];
  int num_partial_torque;
  float partial_torque[kMaxCases * 3];
  int num_cmd_after_clamp;
  float cmd_after_clamp[kMaxCases * 4];
};

// A GoldenController is far too large for an MCU stack frame (19 KiB): each test takes one from the
// shared test scratch (test_scratch.hpp) rather than a static holding it for the whole run.

// A failure label "<controller> <field>[<component>] case <id>" in a static buffer, without
// snprintf (the MCU image has no heap for printf's float formatting).
char g_label[160];
const char* label(const char* ctrl, const char* field, int comp, int id) {
  std::size_t n = 0;
  auto put = [&](const char* s) {
    while (*s != '\0' && n + 1 < sizeof(g_label)) g_label[n++] = *s++;
  };
  auto put_int = [&](int v) {
    char d[12];
    int k = 0;
    if (v < 0) {
      put("-");
      v = -v;
    }
    do {
      d[k++] = static_cast<char>('0' + v % 10);
      v /= 10;
    } while (v > 0 && k < 11);
    while (k > 0 && n + 1 < sizeof(g_label)) g_label[n++] = d[--k];
  };
  put(ctrl);
  put(" ");
  put(field);
  put("[");
  put_int(comp);
  put("] case ");
  put_int(id);
  g_label[n] = '\0';
  return g_label;
}

bool key_is(const char* k, const char* name) { return std::strcmp(k, name) == 0; }

bool read_n(ktest::JsonReader& r, float* out, int n) { return r.read_numbers(out, n) == n; }

bool parse_conventions(ktest::JsonReader& r, Tolerances& tol) {
  static const char* const kNames[] = {"wrench_force_N", "wrench_torque_Nm", "intermediates"};
  Tol* const out[] = {&tol.force, &tol.torque, &tol.inter};
  return ktest::read_conventions_tolerance(r, [&](ktest::JsonReader& t) { return ktest::read_named_tolerances(t, kNames, out, 3); });
}

bool parse_params(ktest::JsonReader& r, GoldenController& c) {
  if (!r.begin_object()) return false;
  char k[64];
  while (r.next_key(k, sizeof k)) {
    bool ok = true;
    if (key_is(k, "mass_kg")) {
      ok = r.read_float(c.mass);
    } else if (key_is(k, "inertia_kgm2")) {
      ok = read_n(r, c.inertia, 9);
    } else if (key_is(k, "gravity_mps2")) {
      ok = read_n(r, c.gravity, 3);
    } else if (key_is(k, "max_yaw_rate_radps")) {
      ok = r.read_float(c.max_yaw_rate);
    } else if (key_is(k, "action_clip")) {
      ok = read_n(r, c.action_clip, 2);
    } else if (key_is(k, "gains")) {
      ok = r.begin_object();
      char g[32];
      while (ok && r.next_key(g, sizeof g)) {
        if (key_is(g, "K_pos")) {
          ok = read_n(r, c.k_pos, 3);
        } else if (key_is(g, "K_vel")) {
          ok = read_n(r, c.k_vel, 3);
        } else if (key_is(g, "K_rot")) {
          ok = read_n(r, c.k_rot, 3);
        } else if (key_is(g, "K_angvel")) {
          ok = read_n(r, c.k_angvel, 3);
        } else {
          ok = r.skip_value();
        }
      }
      ok = ok && r.ok();
    } else {
      ok = r.skip_value();
    }
    if (!ok) return false;
  }
  return r.ok();
}

bool parse_state(ktest::JsonReader& r, GoldenCase& gc) {
  if (!r.begin_object()) return false;
  char k[64];
  while (r.next_key(k, sizeof k)) {
    bool ok = true;
    if (key_is(k, "position_world")) {
      ok = read_n(r, gc.pos, 3);
    } else if (key_is(k, "orientation_xyzw")) {
      ok = read_n(r, gc.quat, 4);
    } else if (key_is(k, "linvel_world")) {
      ok = read_n(r, gc.linvel, 3);
    } else if (key_is(k, "body_angvel")) {
      ok = read_n(r, gc.body_angvel, 3);
    } else if (key_is(k, "euler_angles_rpy")) {
      ok = read_n(r, gc.euler, 3);
    } else if (key_is(k, "vehicle_orientation_xyzw")) {
      ok = read_n(r, gc.vehicle_quat, 4);
    } else if (key_is(k, "vehicle_linvel")) {
      ok = read_n(r, gc.vehicle_linvel, 3);
    } else {
      ok = r.skip_value();
    }
    if (!ok) return false;
  }
  return r.ok();
}

bool parse_intermediate(ktest::JsonReader& r, GoldenCase& gc) {
  if (!r.begin_object()) return false;
  char k[64];
  while (r.next_key(k, sizeof k)) {
    bool ok = true;
    if (key_is(k, "accel_command_world")) {
      ok = gc.has_accel = read_n(r, gc.accel, 3);
    } else if (key_is(k, "desired_quat_xyzw")) {
      ok = gc.has_quat_d = read_n(r, gc.quat_d, 4);
    } else if (key_is(k, "desired_body_angvel_after_yaw_clamp")) {
      ok = gc.has_w_d = read_n(r, gc.w_d, 3);
    } else if (key_is(k, "command_after_in_place_normalization")) {
      ok = gc.has_cmd_after_norm = read_n(r, gc.cmd_after_norm, 7);
    } else {
      ok = r.skip_value();
    }
    if (!ok) return false;
  }
  return r.ok();
}

bool parse_case(ktest::JsonReader& r, GoldenCase& gc) {
  gc = GoldenCase();
  if (!r.begin_object()) return false;
  char k[64];
  while (r.next_key(k, sizeof k)) {
    bool ok = true;
    if (key_is(k, "state")) {
      ok = parse_state(r, gc);
    } else if (key_is(k, "action_raw")) {
      gc.action_len = r.read_numbers(gc.action_raw, 7);
      ok = gc.action_len > 0 && gc.action_len <= 7;
    } else if (key_is(k, "command")) {
      gc.command_len = r.read_numbers(gc.command, 7);
      ok = gc.command_len > 0 && gc.command_len <= 7;
    } else if (key_is(k, "wrench_body")) {
      ok = gc.has_wrench = read_n(r, gc.wrench, 6);
    } else if (key_is(k, "intermediate")) {
      ok = parse_intermediate(r, gc);
    } else {
      ok = r.skip_value();
    }
    if (!ok) return false;
  }
  return r.ok();
}

bool parse_partial_torque(ktest::JsonReader& r, GoldenController& c) {
  if (!r.begin_object()) return false;
  char k[64];
  while (r.next_key(k, sizeof k)) {
    bool ok = true;
    if (key_is(k, "torque_body")) {
      const int n = r.read_numbers(c.partial_torque, kMaxCases * 3);
      ok = n >= 0 && n <= kMaxCases * 3 && n % 3 == 0;
      c.num_partial_torque = n / 3;
    } else if (key_is(k, "command_after_in_place_clamp")) {
      const int n = r.read_numbers(c.cmd_after_clamp, kMaxCases * 4);
      ok = n >= 0 && n <= kMaxCases * 4 && n % 4 == 0;
      c.num_cmd_after_clamp = n / 4;
    } else {
      ok = r.skip_value();
    }
    if (!ok) return false;
  }
  return r.ok();
}

bool parse_controller(ktest::JsonReader& r, GoldenController& c) {
  std::memset(&c, 0, sizeof c);
  if (!r.begin_object()) return false;
  char k[64];
  while (r.next_key(k, sizeof k)) {
    bool ok = true;
    if (key_is(k, "robot")) {
      ok = r.read_string(c.robot, sizeof c.robot);
    } else if (key_is(k, "status")) {
      ok = r.read_string(c.status, sizeof c.status);
    } else if (key_is(k, "params")) {
      ok = parse_params(r, c);
    } else if (key_is(k, "cases")) {
      ok = r.begin_array();
      while (ok && r.next_element()) {
        if (c.num_cases >= kMaxCases) return false;
        ok = parse_case(r, c.cases[c.num_cases]);
        ++c.num_cases;
      }
      ok = ok && r.ok();
    } else if (key_is(k, "partial_torque_only")) {
      ok = parse_partial_torque(r, c);
    } else {
      ok = r.skip_value();
    }
    if (!ok) return false;
  }
  return r.ok();
}

Vec3 vec3_of(const float* v) { return Vec3(static_cast<real>(v[0]), static_cast<real>(v[1]), static_cast<real>(v[2])); }

struct CheckCounts {
  int cases = 0;   // cases whose every value was compared
  int values = 0;  // individual comparisons
};

// Compares mine against golden with the file's rule |a - b| <= abs + rel |b|.
#define GOLDEN_CLOSE(mine, golden, tol, ctrl, field, comp, id)                                          \
  do {                                                                                                 \
    KEXPECT_CLOSE(mine, golden, (tol).abs, (tol).rel, label(ctrl, field, comp, id));                   \
    ++counts.values;                                                                                   \
  } while (0)

// Quaternions are compared up to sign (q and -q are the same rotation).
#define GOLDEN_QUAT(mine_xyzw, golden_xyzw, tol, ctrl, field, id)                                       \
  do {                                                                                                 \
    double dot_ = 0;                                                                                   \
    for (int k_ = 0; k_ < 4; ++k_) dot_ += static_cast<double>(mine_xyzw[k_]) * static_cast<double>(golden_xyzw[k_]); \
    const double sgn_ = dot_ < 0 ? -1.0 : 1.0;                                                         \
    for (int k_ = 0; k_ < 4; ++k_) {                                                                   \
      GOLDEN_CLOSE(sgn_ * static_cast<double>(mine_xyzw[k_]), golden_xyzw[k_], tol, ctrl, field, k_, id); \
    }                                                                                                  \
  } while (0)

CheckCounts check_controller(const char* name, ControllerKind kind, const GoldenController& c, const Tolerances& tol) {
  CheckCounts counts;
  ControllerParams params;
  LeeParams& lp = params.lee;
  lp.mass_kg = static_cast<real>(c.mass);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) lp.inertia_b(i, j) = static_cast<real>(c.inertia[3 * i + j]);
  }
  lp.gravity_w = vec3_of(c.gravity);
  lp.max_yaw_rate_radps = static_cast<real>(c.max_yaw_rate);
  // The file lists the gains the controller held (the midpoints): fix them with min = max.
  lp.gain_ranges.min.k_pos = lp.gain_ranges.max.k_pos = vec3_of(c.k_pos);
  lp.gain_ranges.min.k_vel = lp.gain_ranges.max.k_vel = vec3_of(c.k_vel);
  lp.gain_ranges.min.k_rot = lp.gain_ranges.max.k_rot = vec3_of(c.k_rot);
  lp.gain_ranges.min.k_angvel = lp.gain_ranges.max.k_angvel = vec3_of(c.k_angvel);
  lp.randomize_gains = false;
  lp.action_min = static_cast<real>(c.action_clip[0]);
  lp.action_max = static_cast<real>(c.action_clip[1]);
  KEXPECT_TRUE(validate_lee_params(lp) == Status::ok);

  ControllerState state;
  controller_reset(kind, params, state);
  KEXPECT_TRUE(state.lee.gains.k_angvel == vec3_of(c.k_angvel));

  const bool rates = kind == ControllerKind::lee_rates;
  const bool rov = kind == ControllerKind::rov_fully_actuated;
  const std::size_t dim = controller_action_dim(kind, params);
  if (rates) {
    // The reference cannot run this controller (quirk 1); only its torque routine is defined.
    KEXPECT_EQ(std::strcmp(c.status, "crashes"), 0);
    KEXPECT_EQ(c.num_partial_torque, c.num_cases);
    KEXPECT_EQ(c.num_cmd_after_clamp, c.num_cases);
  } else {
    KEXPECT_EQ(std::strcmp(c.status, "ok"), 0);
  }
  const double g_norm = std::sqrt(static_cast<double>(c.gravity[0]) * c.gravity[0] +
                                  static_cast<double>(c.gravity[1]) * c.gravity[1] +
                                  static_cast<double>(c.gravity[2]) * c.gravity[2]);

  for (int i = 0; i < c.num_cases; ++i) {
    const GoldenCase& gc = c.cases[i];
    const int values_before = counts.values;
    if (gc.action_len != static_cast<int>(dim) || gc.command_len != static_cast<int>(dim)) {
      KEXPECT_EQ(gc.action_len, static_cast<int>(dim));
      continue;
    }
    RigidBodyState body;
    body.position_w = vec3_of(gc.pos);
    body.orientation_wb = quat_from_xyzw(static_cast<real>(gc.quat[0]), static_cast<real>(gc.quat[1]),
                                         static_cast<real>(gc.quat[2]), static_cast<real>(gc.quat[3]));
    body.linvel_w = vec3_of(gc.linvel);
    body.angvel_b = vec3_of(gc.body_angvel);

    // The raw action goes in (the controller clips it itself); a copy shows it is not modified.
    real action[kMaxActionDim] = {};
    real action_copy[kMaxActionDim] = {};
    bool clipped = false;
    for (std::size_t k = 0; k < dim; ++k) {
      action[k] = action_copy[k] = static_cast<real>(gc.action_raw[k]);
      clipped = clipped || gc.action_raw[k] != gc.command[k];
    }
    ControllerOutput out;
    Status st = Status::invalid_argument;
    KEXPECT_NO_HEAP(st = update_controller(kind, params, state, body, action, dim, out));
    KEXPECT_TRUE(st == Status::ok);
    KEXPECT_TRUE(out.is_wrench);
    KEXPECT_EQ(std::memcmp(action, action_copy, sizeof action), 0);  // quirks 2 and 3 not reproduced
    KEXPECT_EQ(state.lee.step_faults, clipped ? static_cast<std::uint32_t>(kFaultCommandOutOfRange) : 0u);

    const Vec3& f = out.wrench_b.force_b;
    const Vec3& t = out.wrench_b.torque_b;
    if (rates) {
      // Thrust: our convention (the reference has none that runs): (command + 1) m |g|.
      const double fz = (static_cast<double>(gc.command[0]) + 1.0) * static_cast<double>(c.mass) * g_norm;
      GOLDEN_CLOSE(f[0], 0.0, tol.force, name, "force", 0, i);
      GOLDEN_CLOSE(f[1], 0.0, tol.force, name, "force", 1, i);
      GOLDEN_CLOSE(f[2], fz, tol.force, name, "force", 2, i);
      for (int k = 0; k < 3; ++k) GOLDEN_CLOSE(t[k], c.partial_torque[3 * i + k], tol.torque, name, "torque", k, i);
      // The reference's clamp of the body-z rate, which it writes into the action buffer; ours is
      // the desired rate in the state.
      const float* after = &c.cmd_after_clamp[4 * i];
      KEXPECT_EQ(after[0], gc.command[0]);
      for (int k = 0; k < 3; ++k) {
        GOLDEN_CLOSE(state.lee.desired_angvel_b[k], after[1 + k], tol.inter, name, "command_after_clamp", 1 + k, i);
      }
    } else {
      KEXPECT_TRUE(gc.has_wrench);
      if (!gc.has_wrench) continue;
      for (int k = 0; k < 3; ++k) GOLDEN_CLOSE(f[k], gc.wrench[k], tol.force, name, "force", k, i);
      for (int k = 0; k < 3; ++k) GOLDEN_CLOSE(t[k], gc.wrench[3 + k], tol.torque, name, "torque", k, i);
    }
    if (gc.has_accel) {
      for (int k = 0; k < 3; ++k) GOLDEN_CLOSE(state.lee.accel_command_w[k], gc.accel[k], tol.inter, name, "accel", k, i);
    }
    if (gc.has_quat_d) GOLDEN_QUAT(state.lee.desired_quat_xyzw, gc.quat_d, tol.inter, name, "desired_quat", i);
    if (gc.has_w_d) {
      for (int k = 0; k < 3; ++k) GOLDEN_CLOSE(state.lee.desired_angvel_b[k], gc.w_d[k], tol.inter, name, "w_d", k, i);
    }
    if (rov) {
      KEXPECT_TRUE(gc.has_cmd_after_norm);
      // The reference's in-place result, sign included, is our (copied) desired quaternion.
      for (int k = 0; k < 4; ++k) {
        GOLDEN_CLOSE(state.lee.desired_quat_xyzw[k], gc.cmd_after_norm[3 + k], tol.inter, name, "cmd_normalized", 3 + k, i);
      }
    }

    // Derived state quantities, which the controller computes itself from the raw quaternion.
    const AttitudeFrame fr = attitude_frame(body.orientation_wb);
    const double yaw_g = static_cast<double>(gc.euler[2]);
    GOLDEN_CLOSE(fr.cos_yaw, std::cos(yaw_g), tol.inter, name, "cos_yaw", 2, i);
    GOLDEN_CLOSE(fr.sin_yaw, std::sin(yaw_g), tol.inter, name, "sin_yaw", 2, i);
    const Vec3 euler = rov ? euler_xyz_two_pi(body.orientation_wb) : euler_xyz(body.orientation_wb);
    for (int k = 0; k < 3; ++k) {
      // Compared on the circle: the golden value may sit on the other side of the wrap point.
      const double d = std::remainder(static_cast<double>(euler[k]) - static_cast<double>(gc.euler[k]), 2.0 * 3.14159265358979323846);
      GOLDEN_CLOSE(d, 0.0, tol.inter, name, "euler", k, i);
    }
    const double yaw_mine = std::atan2(static_cast<double>(fr.sin_yaw), static_cast<double>(fr.cos_yaw));
    const double vq[4] = {0.0, 0.0, std::sin(0.5 * yaw_mine), std::cos(0.5 * yaw_mine)};
    GOLDEN_QUAT(vq, gc.vehicle_quat, tol.inter, name, "vehicle_quat", i);
    const double c_y = static_cast<double>(fr.cos_yaw), s_y = static_cast<double>(fr.sin_yaw);
    const double vx = static_cast<double>(gc.linvel[0]), vy = static_cast<double>(gc.linvel[1]);
    GOLDEN_CLOSE(c_y * vx + s_y * vy, gc.vehicle_linvel[0], tol.inter, name, "vehicle_linvel", 0, i);
    GOLDEN_CLOSE(-s_y * vx + c_y * vy, gc.vehicle_linvel[1], tol.inter, name, "vehicle_linvel", 1, i);

    // A case counts only if all its values were compared.
    const int expected_values = (rates ? 9 : 6) + (gc.has_accel ? 3 : 0) + (gc.has_quat_d ? 4 : 0) +
                                (gc.has_w_d ? 3 : 0) + (rov ? 4 : 0) + 2 + 3 + 4 + 2;
    if (counts.values - values_before == expected_values) ++counts.cases;
  }
  return counts;
}

// Each Lee-family kind (all multirotor kinds but direct_motor) was listed exactly once.
void expect_each_lee_kind_once(const int* seen) {
  for (std::size_t k = 0; k < kNumMultirotorControllerKinds; ++k) {
    if (static_cast<ControllerKind>(k) != ControllerKind::direct_motor) {
      KEXPECT_EQ(seen[k], 1);
    }
  }
}

}  // namespace

KTEST(GoldenControllers, EveryCaseOfEveryControllerMatchesAerialGym) {
  GoldenController& ctrl = ktest::scratch<GoldenController>();
  ktest::JsonReader r;
  KASSERT_TRUE(r.open(ktest::golden_path("controllers.json")));
  KASSERT_TRUE(r.begin_object());
  Tolerances tol;
  bool have_tol = false;
  int cases_in_file[kNumControllerKinds] = {};
  int cases_checked[kNumControllerKinds] = {};
  int values_checked[kNumControllerKinds] = {};
  int seen[kNumControllerKinds] = {};
  char key[64];
  while (r.next_key(key, sizeof key)) {
    if (key_is(key, "conventions")) {
      KASSERT_TRUE(parse_conventions(r, tol));
      have_tol = tol.force.abs >= 0 && tol.force.rel >= 0 && tol.torque.abs >= 0 && tol.torque.rel >= 0 &&
                 tol.inter.abs >= 0 && tol.inter.rel >= 0;
      KASSERT_TRUE(have_tol);
      // The file's tolerances are used as given; guard against a file that loosened them.
      KEXPECT_LE(tol.force.abs, 2e-5);
      KEXPECT_LE(tol.force.rel, 2e-5);
      KEXPECT_LE(tol.torque.abs, 2e-5);
      KEXPECT_LE(tol.torque.rel, 1e-4);
      KEXPECT_LE(tol.inter.abs, 1e-5);
      KEXPECT_LE(tol.inter.rel, 1e-4);
    } else if (key_is(key, "controllers")) {
      KASSERT_TRUE(have_tol);  // conventions precede controllers in the file
      KASSERT_TRUE(r.begin_object());
      char name[64];
      while (r.next_key(name, sizeof name)) {
        KASSERT_TRUE(parse_controller(r, ctrl));
        ControllerKind kind = ControllerKind::direct_motor;
        const bool known = controller_kind_from_name(name, kind);
        KEXPECT_TRUE(known);
        if (!known) continue;
        const CheckCounts n = check_controller(name, kind, ctrl, tol);
        const std::size_t k = static_cast<std::size_t>(kind);
        cases_in_file[k] += ctrl.num_cases;
        cases_checked[k] += n.cases;
        values_checked[k] += n.values;
        ++seen[k];
      }
    } else {
      KASSERT_TRUE(r.skip_value());
    }
  }
  KEXPECT_TRUE(r.ok());
  // A parity test that silently checks nothing must fail: every Lee-family kind appears once with
  // at least one case, and every case the file lists for it was fully compared (any case count).
  expect_each_lee_kind_once(seen);
  for (std::size_t k = 0; k < kNumMultirotorControllerKinds; ++k) {
    if (static_cast<ControllerKind>(k) == ControllerKind::direct_motor) continue;
    KEXPECT_GE(cases_in_file[k], 1);
    KEXPECT_EQ(cases_checked[k], cases_in_file[k]);
    KEXPECT_GE(values_checked[k], cases_in_file[k] * 20);
  }
}

namespace {

// Presets against the params the reference ran with: bit-exact in a float build; a double build
// holds the decimal values of the config (e.g. 0.15, 9.81), within 1e-7 of the float32 ones.
void expect_preset_matches(const LeeParams& p, const GoldenController& c, const char* name) {
  const double rel = sizeof(real) == sizeof(float) ? 0.0 : 1e-7;
  const LeeGains g = lee_nominal_gains(p.gain_ranges);
  KEXPECT_CLOSE(p.mass_kg, c.mass, 0, rel, label(name, "mass", 0, 0));
  for (int i = 0; i < 9; ++i) KEXPECT_CLOSE(p.inertia_b(i / 3, i % 3), c.inertia[i], 0, rel, label(name, "inertia", i, 0));
  for (int k = 0; k < 3; ++k) {
    KEXPECT_CLOSE(p.gravity_w[k], c.gravity[k], 0, rel, label(name, "gravity", k, 0));
    KEXPECT_CLOSE(g.k_pos[k], c.k_pos[k], 0, rel, label(name, "K_pos", k, 0));
    KEXPECT_CLOSE(g.k_vel[k], c.k_vel[k], 0, rel, label(name, "K_vel", k, 0));
    KEXPECT_CLOSE(g.k_rot[k], c.k_rot[k], 0, rel, label(name, "K_rot", k, 0));
    KEXPECT_CLOSE(g.k_angvel[k], c.k_angvel[k], 0, rel, label(name, "K_angvel", k, 0));
  }
  // max_yaw_rate is listed as the float64 pi/3 to 9 digits; the reference clamps with float32(pi/3).
  KEXPECT_CLOSE(p.max_yaw_rate_radps, c.max_yaw_rate, 0, 1e-7, label(name, "max_yaw_rate", 0, 0));
  KEXPECT_EQ(p.action_min, static_cast<real>(c.action_clip[0]));
  KEXPECT_EQ(p.action_max, static_cast<real>(c.action_clip[1]));
}

}  // namespace

KTEST(GoldenControllers, PresetsMatchReferenceParams) {
  GoldenController& ctrl = ktest::scratch<GoldenController>();
  ktest::JsonReader r;
  KASSERT_TRUE(r.open(ktest::golden_path("controllers.json")));
  KASSERT_TRUE(r.begin_object());
  KASSERT_TRUE(r.find_key("controllers"));
  KASSERT_TRUE(r.begin_object());
  int seen[kNumControllerKinds] = {};
  char name[64];
  while (r.next_key(name, sizeof name)) {
    KASSERT_TRUE(parse_controller(r, ctrl));
    const bool rov = key_is(ctrl.robot, "base_rov");
    KEXPECT_TRUE(rov || key_is(ctrl.robot, "base_quadrotor"));
    expect_preset_matches(rov ? lee_params_rov() : lee_params_base_quadrotor(), ctrl, name);
    ControllerKind kind = ControllerKind::direct_motor;
    KEXPECT_TRUE(controller_kind_from_name(name, kind));
    ++seen[static_cast<std::size_t>(kind)];
  }
  KEXPECT_TRUE(r.ok());
  expect_each_lee_kind_once(seen);
}
