// Fuzz target: the C API (platform/capi, kestrel/kestrel.h) as firmware would drive it.
// Byte 0 picks the preset, byte 1 a mask of kestrel_params groups to override (the rest from
// kestrel_default_params), then kestrel_init_params and up to 256 records: set the whole state /
// one state component / the setpoint (valid or raw mode) / dt_s, inject a motor failure, clear
// faults, kestrel_command_to_pwm_us, or 1-4 kestrel_step calls. Every float is a table entry (0,
// +-1, NaN, +-inf, FLT_MAX, denormals, 1e10, 1e30, ...) or 4 raw bytes.
//
// Oracles (kestrel.h):
//  - after a failed init, kestrel_step returns KESTREL_INVALID_ARGUMENT;
//  - KESTREL_INVALID_ARGUMENT leaves `out` unchanged; a bad mode, dt_s outside (0, KESTREL_MAX_DT_S]
//    or a finite quaternion off unit length (beyond the tolerance) gives it;
//  - any other status: every output finite, motor_command in [0, 1], out.faults == kestrel_faults();
//  - KESTREL_OK: every input was finite and no NON_FINITE_* fault bit was newly raised;
//  - a non-finite state or setpoint value never gives KESTREL_OK;
//  - kestrel_command_to_pwm_us stays in [min_us, max_us] (up to rounding) for a finite, ordered range.
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "fuzz_common.hpp"
#include "kestrel/kestrel.h"

namespace {

struct Reader {
  const std::uint8_t* p;
  std::size_t n;
  bool empty() const { return n == 0; }
  std::uint8_t byte() {
    if (n == 0) return 0;
    --n;
    return *p++;
  }
  float real() {
    static const float kTable[16] = {0.0f, 1.0f, -1.0f, 0.5f, std::numeric_limits<float>::quiet_NaN(),
                                     std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                                     FLT_MAX, -FLT_MAX, FLT_MIN, 1e-40f, 1e10f, 1e30f, -1e30f, 0.01f, 9.81f};
    const std::uint8_t t = byte();
    if (!(t & 0x80)) return kTable[t & 15];
    std::uint8_t b[4] = {byte(), byte(), byte(), byte()};
    float f;
    std::memcpy(&f, b, 4);
    return f;
  }
};

bool quat_ok(const float* q) {  // finite and unit within the tolerance (with rounding slack both ways)
  const double n = std::sqrt(static_cast<double>(q[0]) * q[0] + static_cast<double>(q[1]) * q[1] +
                             static_cast<double>(q[2]) * q[2] + static_cast<double>(q[3]) * q[3]);
  return std::fabs(n - 1.0) <= static_cast<double>(KESTREL_QUAT_NORM_TOLERANCE);
}

void check_step(kestrel_storage& st, bool init_ok, const kestrel_state& x, const kestrel_setpoint& sp, float dt,
                kestrel_output& out) {
  constexpr std::uint32_t kNonFinite =
      KESTREL_FAULT_NON_FINITE_COMMAND | KESTREL_FAULT_NON_FINITE_STATE | KESTREL_FAULT_NON_FINITE_OUTPUT;
  const std::uint32_t before = init_ok ? kestrel_faults(&st) : 0;
  kestrel_output prev;
  std::memcpy(&prev, &out, sizeof out);
  const kestrel_status s = kestrel_step(&st, &x, &sp, dt, &out);
  if (!init_ok) KFUZZ_CHECK(s == KESTREL_INVALID_ARGUMENT, "step after a failed init returned %d", static_cast<int>(s));
  const bool mode_ok = sp.mode == KESTREL_MODE_POSITION || sp.mode == KESTREL_MODE_VELOCITY ||
                       sp.mode == KESTREL_MODE_ATTITUDE || sp.mode == KESTREL_MODE_RATES;
  const bool dt_ok = dt > 0.0f && dt <= KESTREL_MAX_DT_S;
  const bool q_finite = kfuzz::all_finite(x.orientation_xyzw, 4);
  const double qn = std::sqrt(static_cast<double>(x.orientation_xyzw[0]) * x.orientation_xyzw[0] +
                              static_cast<double>(x.orientation_xyzw[1]) * x.orientation_xyzw[1] +
                              static_cast<double>(x.orientation_xyzw[2]) * x.orientation_xyzw[2] +
                              static_cast<double>(x.orientation_xyzw[3]) * x.orientation_xyzw[3]);
  if (!mode_ok || !dt_ok || (q_finite && std::fabs(qn - 1.0) > 2.0 * KESTREL_QUAT_NORM_TOLERANCE))
    KFUZZ_CHECK(s == KESTREL_INVALID_ARGUMENT, "mode %d, dt %g, |q| %g: status %d", static_cast<int>(sp.mode),
                static_cast<double>(dt), qn, static_cast<int>(s));
  if (s == KESTREL_INVALID_ARGUMENT) {
    KFUZZ_CHECK(std::memcmp(&prev, &out, sizeof out) == 0, "INVALID_ARGUMENT changed the output");
    return;
  }
  const bool inputs_finite = kfuzz::all_finite(x.position_w, 3) && q_finite && kfuzz::all_finite(x.linvel_w, 3) &&
                             kfuzz::all_finite(x.angvel_b, 3) && kfuzz::all_finite(sp.value, 4);
  KFUZZ_CHECK(out.num_motors >= 1 && out.num_motors <= KESTREL_MAX_MOTORS, "num_motors %d", static_cast<int>(out.num_motors));
  for (int i = 0; i < out.num_motors; ++i) {
    KFUZZ_CHECK(out.motor_command[i] >= 0.0f && out.motor_command[i] <= 1.0f, "status %d: motor_command[%d] = %g",
                static_cast<int>(s), i, static_cast<double>(out.motor_command[i]));
    KFUZZ_CHECK(std::isfinite(out.thrust_setpoint_N[i]) && std::isfinite(out.thrust_N[i]), "status %d: thrust %d not finite",
                static_cast<int>(s), i);
  }
  KFUZZ_CHECK(kfuzz::all_finite(out.wrench_b, 6), "status %d: wrench not finite", static_cast<int>(s));
  KFUZZ_CHECK(out.faults == kestrel_faults(&st), "out.faults 0x%x, kestrel_faults 0x%x", out.faults, kestrel_faults(&st));
  if (s == KESTREL_OK) {
    KFUZZ_CHECK(inputs_finite, "KESTREL_OK with a non-finite input");
    KFUZZ_CHECK(quat_ok(x.orientation_xyzw) || std::fabs(qn - 1.0) <= 1.01 * KESTREL_QUAT_NORM_TOLERANCE,
                "KESTREL_OK with |q| = %.9g", qn);
    KFUZZ_CHECK(((out.faults & ~before) & kNonFinite) == 0, "KESTREL_OK but new fault bits 0x%x",
                (out.faults & ~before) & kNonFinite);
  }
  if (!inputs_finite) KFUZZ_CHECK(s == KESTREL_NON_FINITE_INPUT, "non-finite input gave status %d", static_cast<int>(s));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader r{data, size};
  static const std::int32_t kPresets[8] = {KESTREL_PRESET_BASE_QUADROTOR, KESTREL_PRESET_HEXAROTOR, KESTREL_PRESET_X500,
                                           KESTREL_PRESET_BASE_QUADROTOR, 1, -1, 99, KESTREL_PRESET_X500};
  const std::int32_t preset = kPresets[r.byte() & 7];
  const std::uint8_t mask = r.byte();
  kestrel_params p;
  std::memset(&p, 0, sizeof p);
  if (kestrel_default_params(preset, &p) != KESTREL_OK) {
    (void)kestrel_default_params(KESTREL_PRESET_BASE_QUADROTOR, &p);
    p.preset = preset;
  }
  auto fill = [&](float* v, int n) {
    for (int i = 0; i < n; ++i) v[i] = r.real();
  };
  if (mask & 0x01) p.mass_kg = r.real();
  if (mask & 0x02) fill(p.inertia_diag_kgm2, 3);
  if (mask & 0x04) fill(p.k_pos, 3);
  if (mask & 0x08) fill(p.k_vel, 3);
  if (mask & 0x10) fill(p.k_rot, 3);
  if (mask & 0x20) fill(p.k_angvel, 3);
  if (mask & 0x40) {
    p.max_yaw_rate_radps = r.real();
    p.yaw_headroom = r.real();
  }
  if (mask & 0x80) p.use_motor_model = static_cast<std::int8_t>(r.byte());

  kestrel_storage st;
  std::memset(&st, 0xA5, sizeof st);
  const bool init_ok = kestrel_init_params(&st, &p) == KESTREL_OK;
  kestrel_state x = {{0, 0, 1}, {0, 0, 0, 1}, {0, 0, 0}, {0, 0, 0}};
  kestrel_setpoint sp = {KESTREL_MODE_POSITION, {0, 0, 1, 0}};
  float dt = 0.01f;
  kestrel_output out;
  std::memset(&out, 0, sizeof out);
  if (!init_ok) check_step(st, init_ok, x, sp, dt, out);

  for (int rec = 0; rec < 256 && !r.empty(); ++rec) {
    switch (r.byte() & 7) {
      case 0:
        fill(x.position_w, 3), fill(x.orientation_xyzw, 4), fill(x.linvel_w, 3), fill(x.angvel_b, 3);
        break;
      case 1: {
        float* comp[13] = {&x.position_w[0], &x.position_w[1], &x.position_w[2], &x.orientation_xyzw[0],
                           &x.orientation_xyzw[1], &x.orientation_xyzw[2], &x.orientation_xyzw[3], &x.linvel_w[0],
                           &x.linvel_w[1], &x.linvel_w[2], &x.angvel_b[0], &x.angvel_b[1], &x.angvel_b[2]};
        float* c = comp[r.byte() % 13];
        *c = r.real();
        break;
      }
      case 2: {
        static const std::int32_t kModes[8] = {KESTREL_MODE_POSITION, KESTREL_MODE_VELOCITY, KESTREL_MODE_ATTITUDE,
                                               KESTREL_MODE_RATES, 2, -1, 5, 1 << 30};
        const std::uint8_t m = r.byte();
        sp.mode = (m & 0x80) ? static_cast<std::int32_t>(m & 0x7f) - 8 : kModes[m & 7];
        fill(sp.value, 4);
        break;
      }
      case 3:
        dt = r.real();
        break;
      case 4: {
        const std::int32_t motor = static_cast<std::int8_t>(r.byte());
        const float scale = r.real();
        if (init_ok) (void)kestrel_inject_motor_failure(&st, motor, scale);
        break;
      }
      case 5:
        if (init_ok) kestrel_clear_faults(&st);
        break;
      case 6: {
        const float c = r.real(), lo = r.real(), hi = r.real();
        const float us = kestrel_command_to_pwm_us(c, lo, hi);
        if (std::isfinite(lo) && std::isfinite(hi) && lo <= hi && std::isfinite(hi - lo))
          // min + c (max - min) rounds: allow a few ulps of the larger end.
          KFUZZ_CHECK(us >= lo - 1e-6f * std::fmax(std::fabs(lo), std::fabs(hi)) &&
                          us <= hi + 1e-6f * std::fmax(std::fabs(lo), std::fabs(hi)),
                      "pwm(%g, %g, %g) = %g", static_cast<double>(c),
                      static_cast<double>(lo), static_cast<double>(hi), static_cast<double>(us));
        break;
      }
      default: {
        const int k = 1 + (r.byte() & 3);
        for (int i = 0; i < k; ++i) check_step(st, init_ok, x, sp, dt, out);
        break;
      }
    }
  }
  return 0;
}
