/* The C API (kestrel/kestrel.h) used from plain C99, as a C flight firmware would: static storage,
 * init from a preset, a fixed-rate loop, motor commands, faults, a motor failure. The same
 * program runs on the host (ctest capi.host) and on the emulated Cortex-M4F (ctest
 * kestrel_capi_test under QEMU). Exit status 0 = every check passed.
 *
 * The loop is closed with a small rigid-body plant written here in C (semi-implicit Euler) for
 * the base quadrotor, whose geometry the test knows: rotors at (+-0.13, +-0.13) m, directions
 * [1, -1, 1, -1], reaction torque ratio 0.01 (allocation/presets.hpp). */
#include <stdint.h>
#include <string.h>

#include "kestrel/kestrel.h"

void capi_test_print(const char* s);
void capi_test_print_fixed(double v, int decimals);
void capi_test_print_int(long v);

static int g_failures = 0;

static void check(int ok, const char* what) {
  if (!ok) {
    capi_test_print("FAIL: ");
    capi_test_print(what);
    capi_test_print("\n");
    ++g_failures;
  }
}

static float absf(float v) { return v < 0.0f ? -v : v; }
static float sqrtf_newton(float v) {
  /* Only for reporting the error norm; avoids libm in the test program. */
  float x = v > 1.0f ? v : 1.0f;
  int i;
  if (v <= 0.0f) return 0.0f;
  for (i = 0; i < 30; ++i) x = 0.5f * (x + v / x);
  return x;
}

/* Storage of the stacks under test: static, as on a flight controller. */
static kestrel_storage g_quad;
static kestrel_storage g_quad_twin;
static kestrel_storage g_hexa;

typedef struct plant {
  float p[3], v[3], q[4], w[3]; /* q xyzw */
} plant;

static void plant_to_state(const plant* b, kestrel_state* s) {
  memcpy(s->position_w, b->p, sizeof b->p);
  memcpy(s->orientation_xyzw, b->q, sizeof b->q);
  memcpy(s->linvel_w, b->v, sizeof b->v);
  memcpy(s->angvel_b, b->w, sizeof b->w);
}

/* One step of the quadrotor plant with the motors' thrusts (N). */
static void plant_step(plant* b, const float* f, float dt) {
  static const float rx[4] = {0.13f, -0.13f, -0.13f, 0.13f};
  static const float ry[4] = {-0.13f, -0.13f, 0.13f, 0.13f};
  static const float dir[4] = {1.0f, -1.0f, 1.0f, -1.0f};
  const float m = 0.25f, jx = 0.000845f, jy = 0.000845f, jz = 0.00169f;
  float fz = 0.0f, tx = 0.0f, ty = 0.0f, tz = 0.0f;
  float x = b->q[0], y = b->q[1], z = b->q[2], w = b->q[3], n;
  float ax, ay, az, dwx, dwy, dwz, qx, qy, qz, qw;
  int i;
  for (i = 0; i < 4; ++i) {
    fz += f[i];
    tx += ry[i] * f[i];
    ty += -rx[i] * f[i];
    tz += -dir[i] * 0.01f * f[i];
  }
  /* World acceleration: R e_z fz / m + g (third column of R). */
  ax = 2.0f * (x * z + w * y) * fz / m;
  ay = 2.0f * (y * z - w * x) * fz / m;
  az = (1.0f - 2.0f * (x * x + y * y)) * fz / m - 9.81f;
  dwx = (tx - (jz - jy) * b->w[1] * b->w[2]) / jx;
  dwy = (ty - (jx - jz) * b->w[2] * b->w[0]) / jy;
  dwz = (tz - (jy - jx) * b->w[0] * b->w[1]) / jz;
  b->v[0] += ax * dt;
  b->v[1] += ay * dt;
  b->v[2] += az * dt;
  b->w[0] += dwx * dt;
  b->w[1] += dwy * dt;
  b->w[2] += dwz * dt;
  for (i = 0; i < 3; ++i) b->p[i] += b->v[i] * dt;
  /* q += dt/2 q (x) (w, 0), then normalise. */
  qx = 0.5f * dt * (w * b->w[0] + y * b->w[2] - z * b->w[1]);
  qy = 0.5f * dt * (w * b->w[1] + z * b->w[0] - x * b->w[2]);
  qz = 0.5f * dt * (w * b->w[2] + x * b->w[1] - y * b->w[0]);
  qw = 0.5f * dt * (-x * b->w[0] - y * b->w[1] - z * b->w[2]);
  x += qx;
  y += qy;
  z += qz;
  w += qw;
  n = sqrtf_newton(x * x + y * y + z * z + w * w);
  b->q[0] = x / n;
  b->q[1] = y / n;
  b->q[2] = z / n;
  b->q[3] = w / n;
  if (b->p[2] < 0.0f) { /* ground */
    b->p[2] = 0.0f;
    if (b->v[2] < 0.0f) b->v[0] = b->v[1] = b->v[2] = 0.0f;
    b->w[0] = b->w[1] = b->w[2] = 0.0f;
  }
}

static void test_arguments(void) {
  kestrel_params p;
  kestrel_state s;
  kestrel_setpoint sp;
  kestrel_output out;
  static kestrel_storage never_initialised;
  memset(&s, 0, sizeof s);
  s.orientation_xyzw[3] = 1.0f;
  memset(&sp, 0, sizeof sp);
  check(kestrel_storage_used() <= KESTREL_STORAGE_BYTES, "storage fits");
  check(kestrel_init(&g_quad, 99) == KESTREL_INVALID_ARGUMENT, "unknown preset rejected");
  check(kestrel_default_params(KESTREL_PRESET_BASE_QUADROTOR, &p) == KESTREL_OK, "default params");
  p.mass_kg = -1.0f;
  check(kestrel_init_params(&g_quad, &p) == KESTREL_INVALID_ARGUMENT, "negative mass rejected");
  check(kestrel_step(&g_quad, &s, &sp, 0.002f, &out) == KESTREL_INVALID_ARGUMENT, "failed init leaves storage unusable");
  check(kestrel_step(&never_initialised, &s, &sp, 0.002f, &out) == KESTREL_INVALID_ARGUMENT, "zeroed storage unusable");
  check(kestrel_init(&g_quad, KESTREL_PRESET_BASE_QUADROTOR) == KESTREL_OK, "init quad");
  check(kestrel_step(&g_quad, &s, &sp, 0.0f, &out) == KESTREL_INVALID_ARGUMENT, "dt = 0 rejected");
  sp.mode = 2; /* acceleration control: not exposed */
  check(kestrel_step(&g_quad, &s, &sp, 0.002f, &out) == KESTREL_INVALID_ARGUMENT, "unknown mode rejected");
  check(kestrel_inject_motor_failure(&g_quad, 4, 0.0f) == KESTREL_INVALID_ARGUMENT, "motor index checked");
  check(absf(kestrel_command_to_pwm_us(0.5f, 1000.0f, 2000.0f) - 1500.0f) < 1e-3f, "pwm mid");
  check(kestrel_command_to_pwm_us(2.0f, 1000.0f, 2000.0f) == 2000.0f, "pwm clamps");
}

/* v - v is 0 for a finite v and NaN for NaN or +-inf (no libm on the MCU side needed). */
static int finitef_(float v) { return v - v == 0.0f; }

/* Every output finite, motor_command in [0, 1] (the API's contract for any input). */
static int outputs_sane(const kestrel_output* o) {
  int ok = o->num_motors > 0 && o->num_motors <= KESTREL_MAX_MOTORS;
  int i;
  for (i = 0; i < KESTREL_MAX_MOTORS; ++i) {
    ok = ok && o->motor_command[i] >= 0.0f && o->motor_command[i] <= 1.0f;
    ok = ok && finitef_(o->thrust_setpoint_N[i]) && finitef_(o->thrust_N[i]);
  }
  for (i = 0; i < 6; ++i) ok = ok && finitef_(o->wrench_b[i]);
  return ok;
}

/* Fuzz findings F1, F6, F7 (docs/notes/fuzz.md), motor model off and on. */
static void test_fuzz_findings(void) {
  int motors;
  for (motors = 0; motors <= 1; ++motors) {
    kestrel_params p;
    kestrel_state x;
    kestrel_setpoint sp;
    kestrel_output o, held;
    kestrel_status st;
    int i;
    memset(&x, 0, sizeof x);
    memset(&sp, 0, sizeof sp);
    x.position_w[2] = 1.0f;
    x.orientation_xyzw[3] = 1.0f;
    sp.mode = KESTREL_MODE_POSITION;
    sp.value[2] = 1.0f;
    check(kestrel_default_params(KESTREL_PRESET_BASE_QUADROTOR, &p) == KESTREL_OK, "F1: default params");
    p.use_motor_model = motors;

    /* F1 (the reproducer): body rate 3.4e38 rad/s as the very first step -> NaN motor commands
     * with KESTREL_OK before the fix. Now: held (zero: nothing held yet), finite, not OK. */
    check(kestrel_init_params(&g_quad, &p) == KESTREL_OK, "F1: init");
    x.angvel_b[2] = 3.4e38f;
    st = kestrel_step(&g_quad, &x, &sp, 0.01f, &o);
    check(st == KESTREL_NON_FINITE_OUTPUT, "F1: 3.4e38 rad/s body rate is not OK");
    check(outputs_sane(&o), "F1: 3.4e38 rad/s body rate gives finite outputs, commands in [0, 1]");
    check((o.faults & KESTREL_FAULT_NON_FINITE_OUTPUT) != 0, "F1: non-finite-output fault latched");
    /* A sane step, then the absurd rate again: the last finite thrusts are held. */
    x.angvel_b[2] = 0.0f;
    check(kestrel_step(&g_quad, &x, &sp, 0.01f, &held) == KESTREL_OK, "F1: sane step after the hold is OK");
    check(outputs_sane(&held), "F1: sane step outputs");
    x.angvel_b[2] = 3.4e38f;
    check(kestrel_step(&g_quad, &x, &sp, 0.01f, &o) == KESTREL_NON_FINITE_OUTPUT, "F1: absurd rate again not OK");
    check(outputs_sane(&o), "F1: absurd rate again sane outputs");
    for (i = 0; i < o.num_motors; ++i) {
      check(o.thrust_setpoint_N[i] == held.thrust_setpoint_N[i], "F1: last finite thrust held");
      check(o.motor_command[i] == held.motor_command[i], "F1: last finite command held");
    }
    /* The held controller wrench is now the huge finite one: a NaN setpoint must not bring NaN. */
    sp.value[0] = 0.0f / (sp.value[1] + 0.0f); /* NaN without <math.h> */
    check(kestrel_step(&g_quad, &x, &sp, 0.01f, &o) != KESTREL_OK, "F1: NaN setpoint after absurd rate not OK");
    check(outputs_sane(&o), "F1: NaN setpoint after absurd rate sane outputs");
    sp.value[0] = 0.0f;
    x.angvel_b[2] = 0.0f;
    check(kestrel_step(&g_quad, &x, &sp, 0.01f, &o) == KESTREL_OK && outputs_sane(&o), "F1: recovers");

    /* F1, second trigger: k_angvel.z = 1e37 (with 10 rad/s, 1e38 N m) is refused at init. */
    p.k_angvel[2] = 1e37f;
    check(kestrel_init_params(&g_quad, &p) == KESTREL_INVALID_ARGUMENT, "F1: k_angvel.z = 1e37 refused");
    check(kestrel_step(&g_quad, &x, &sp, 0.01f, &o) == KESTREL_INVALID_ARGUMENT, "F1: refused init leaves it unusable");
    p.k_angvel[2] = 1e6f; /* the bound itself is accepted: outputs stay sane at 10 rad/s */
    check(kestrel_init_params(&g_quad, &p) == KESTREL_OK, "F1: k_angvel.z = 1e6 accepted");
    x.angvel_b[2] = 10.0f;
    st = kestrel_step(&g_quad, &x, &sp, 0.01f, &o);
    check(st == KESTREL_OK || st == KESTREL_NON_FINITE_OUTPUT, "F1: gain at the bound");
    check(outputs_sane(&o), "F1: gain at the bound sane outputs");
    x.angvel_b[2] = 0.0f;

    /* F6: dt_s is bounded by KESTREL_MAX_DT_S. */
    check(kestrel_init(&g_quad, KESTREL_PRESET_HEXAROTOR) == KESTREL_OK, "F6: init hexa");
    check(kestrel_step(&g_quad, &x, &sp, 1e18f, &o) == KESTREL_INVALID_ARGUMENT, "F6: dt 1e18 s refused");
    check(kestrel_step(&g_quad, &x, &sp, 1.5f, &o) == KESTREL_INVALID_ARGUMENT, "F6: dt above 1 s refused");
    check(kestrel_step(&g_quad, &x, &sp, KESTREL_MAX_DT_S, &o) == KESTREL_OK, "F6: dt of 1 s accepted");
    check(outputs_sane(&o), "F6: dt of 1 s sane outputs");

    /* F7: a finite non-unit quaternion is refused. */
    check(kestrel_init_params(&g_quad, &p) == KESTREL_OK, "F7: init");
    x.orientation_xyzw[3] = 0.0f;
    check(kestrel_step(&g_quad, &x, &sp, 0.01f, &o) == KESTREL_INVALID_ARGUMENT, "F7: zero quaternion refused");
    x.orientation_xyzw[3] = 1000.0f;
    check(kestrel_step(&g_quad, &x, &sp, 0.01f, &o) == KESTREL_INVALID_ARGUMENT, "F7: |q| = 1000 refused");
    x.orientation_xyzw[3] = 1.0f + 2.0f * KESTREL_QUAT_NORM_TOLERANCE;
    check(kestrel_step(&g_quad, &x, &sp, 0.01f, &o) == KESTREL_INVALID_ARGUMENT, "F7: |q| = 1 + 2 tol refused");
    x.orientation_xyzw[3] = 1.0f + 0.5f * KESTREL_QUAT_NORM_TOLERANCE;
    check(kestrel_step(&g_quad, &x, &sp, 0.01f, &o) == KESTREL_OK, "F7: |q| = 1 + tol/2 accepted");
    x.orientation_xyzw[3] = 0.0f / (x.orientation_xyzw[0] + 0.0f); /* NaN: a non-finite input */
    check(kestrel_step(&g_quad, &x, &sp, 0.01f, &o) == KESTREL_NON_FINITE_INPUT, "F7: NaN quaternion is non-finite input");
    check(outputs_sane(&o), "F7: NaN quaternion sane outputs");
  }
}

/* Take off to 1 m, then fly to (0.5, -0.3, 1.2) with yaw 0.3; 8 s at 500 Hz. */
static void test_closed_loop_quad(void) {
  const float dt = 0.002f;
  plant b;
  kestrel_state s;
  kestrel_setpoint sp;
  kestrel_output out, out_twin;
  float err = 0.0f, e0, e1, e2;
  int k, in_range = 1, identical = 1;
  memset(&b, 0, sizeof b);
  b.q[3] = 1.0f;
  check(kestrel_init(&g_quad, KESTREL_PRESET_BASE_QUADROTOR) == KESTREL_OK, "init quad");
  check(kestrel_init(&g_quad_twin, KESTREL_PRESET_BASE_QUADROTOR) == KESTREL_OK, "init twin");
  sp.mode = KESTREL_MODE_POSITION;
  for (k = 0; k < 4000; ++k) {
    int i;
    const int second = k >= 2000;
    sp.value[0] = second ? 0.5f : 0.0f;
    sp.value[1] = second ? -0.3f : 0.0f;
    sp.value[2] = second ? 1.2f : 1.0f;
    sp.value[3] = second ? 0.3f : 0.0f;
    plant_to_state(&b, &s);
    check(kestrel_step(&g_quad, &s, &sp, dt, &out) == KESTREL_OK, "step ok");
    (void)kestrel_step(&g_quad_twin, &s, &sp, dt, &out_twin);
    /* Field by field: the struct's padding bytes are never written. */
    if (memcmp(out.thrust_setpoint_N, out_twin.thrust_setpoint_N, sizeof out.thrust_setpoint_N) != 0 ||
        memcmp(out.thrust_N, out_twin.thrust_N, sizeof out.thrust_N) != 0 ||
        memcmp(out.motor_command, out_twin.motor_command, sizeof out.motor_command) != 0 ||
        memcmp(out.wrench_b, out_twin.wrench_b, sizeof out.wrench_b) != 0 || out.faults != out_twin.faults) {
      identical = 0;
    }
    for (i = 0; i < out.num_motors; ++i) {
      if (!(out.motor_command[i] >= 0.0f && out.motor_command[i] <= 1.0f)) in_range = 0;
    }
    plant_step(&b, out.thrust_N, dt);
  }
  e0 = b.p[0] - 0.5f;
  e1 = b.p[1] + 0.3f;
  e2 = b.p[2] - 1.2f;
  err = sqrtf_newton(e0 * e0 + e1 * e1 + e2 * e2);
  capi_test_print("  quad closed loop (C plant): final position error ");
  capi_test_print_fixed((double)err * 1000.0, 2);
  capi_test_print(" mm, motor commands ");
  capi_test_print_fixed((double)out.motor_command[0], 3);
  capi_test_print(" ");
  capi_test_print_fixed((double)out.motor_command[1], 3);
  capi_test_print(" ");
  capi_test_print_fixed((double)out.motor_command[2], 3);
  capi_test_print(" ");
  capi_test_print_fixed((double)out.motor_command[3], 3);
  capi_test_print(", PWM ");
  capi_test_print_fixed((double)kestrel_command_to_pwm_us(out.motor_command[0], 1000.0f, 2000.0f), 1);
  capi_test_print(" us\n");
  check(out.num_motors == 4, "quad has 4 motors");
  check(err < 0.05f, "quad reaches the setpoint within 5 cm");
  check(in_range, "motor commands in [0, 1]");
  check(identical, "two storages, same inputs: bit-identical outputs");
  check((kestrel_faults(&g_quad) & (KESTREL_FAULT_NON_FINITE_STATE | KESTREL_FAULT_NON_FINITE_OUTPUT |
                                    KESTREL_FAULT_MOTOR_FAILURE)) == 0u,
        "no unexpected faults");

  /* NaN in the state: rejected, last safe output held, fault latched, outputs finite. */
  {
    kestrel_output held;
    int i, finite = 1;
    s.position_w[0] = 0.0f / 0.0f;
    check(kestrel_step(&g_quad, &s, &sp, dt, &held) == KESTREL_NON_FINITE_INPUT, "NaN state rejected");
    for (i = 0; i < 4; ++i) finite = finite && held.thrust_setpoint_N[i] == held.thrust_setpoint_N[i];
    check(finite, "outputs stay finite");
    check((kestrel_faults(&g_quad) & KESTREL_FAULT_NON_FINITE_STATE) != 0u, "non-finite state latched");
    kestrel_clear_faults(&g_quad);
    check((kestrel_faults(&g_quad) & KESTREL_FAULT_NON_FINITE_STATE) == 0u, "faults cleared");
  }
}

/* Hexarotor at hover: motor 0 dies; the allocator gives it zero and the other five still carry
 * the weight with no net roll/pitch torque (geometry of allocation/presets.hpp, hexarotor()). */
static void test_hexa_motor_failure(void) {
  static const float rx[6] = {0.216506351f, 0.216506351f, 0.0f, -0.216506351f, -0.216506351f, 0.0f};
  static const float ry[6] = {-0.125f, 0.125f, 0.25f, 0.125f, -0.125f, -0.25f};
  kestrel_params p;
  kestrel_state s;
  kestrel_setpoint sp;
  kestrel_output out;
  float fz = 0.0f, tx = 0.0f, ty = 0.0f;
  int i;
  memset(&s, 0, sizeof s);
  s.position_w[2] = 1.0f;
  s.orientation_xyzw[3] = 1.0f;
  sp.mode = KESTREL_MODE_POSITION;
  sp.value[0] = 0.0f;
  sp.value[1] = 0.0f;
  sp.value[2] = 1.0f;
  sp.value[3] = 0.0f;
  check(kestrel_default_params(KESTREL_PRESET_HEXAROTOR, &p) == KESTREL_OK, "hexa params");
  p.use_motor_model = 0;
  check(kestrel_init_params(&g_hexa, &p) == KESTREL_OK, "init hexa");
  check(kestrel_step(&g_hexa, &s, &sp, 0.002f, &out) == KESTREL_OK, "hexa step");
  check(out.num_motors == 6, "hexa has 6 motors");
  check(absf(out.motor_command[0] - out.motor_command[3]) < 1e-4f, "healthy hexa: symmetric commands");
  check(kestrel_inject_motor_failure(&g_hexa, 0, 0.0f) == KESTREL_OK, "inject failure");
  check((kestrel_faults(&g_hexa) & KESTREL_FAULT_MOTOR_FAILURE) != 0u, "motor failure flagged");
  (void)kestrel_step(&g_hexa, &s, &sp, 0.002f, &out);
  for (i = 0; i < 6; ++i) {
    fz += out.thrust_setpoint_N[i];
    tx += ry[i] * out.thrust_setpoint_N[i];
    ty += -rx[i] * out.thrust_setpoint_N[i];
  }
  capi_test_print("  hexarotor, motor 1 dead: thrust ");
  capi_test_print_fixed((double)fz, 3);
  capi_test_print(" N (weight ");
  capi_test_print_fixed((double)(p.mass_kg * 9.81f), 3);
  capi_test_print(" N), commands");
  for (i = 0; i < 6; ++i) {
    capi_test_print(" ");
    capi_test_print_fixed((double)out.motor_command[i], 3);
  }
  capi_test_print("\n");
  check(out.thrust_setpoint_N[0] == 0.0f, "dead motor gets zero");
  check(absf(fz - p.mass_kg * 9.81f) < 0.01f * p.mass_kg * 9.81f, "weight still carried");
  check(absf(tx) < 1e-3f && absf(ty) < 1e-3f, "no roll/pitch torque left");
}

int main(void) {
  capi_test_print("kestrel C API test\n");
  test_arguments();
  test_closed_loop_quad();
  test_hexa_motor_failure();
  test_fuzz_findings();
  capi_test_print("  storage used ");
  capi_test_print_int((long)kestrel_storage_used());
  capi_test_print(" of ");
  capi_test_print_int((long)KESTREL_STORAGE_BYTES);
  capi_test_print(" bytes\n");
  capi_test_print(g_failures == 0 ? "capi: PASS\n" : "capi: FAIL\n");
  return g_failures == 0 ? 0 : 1;
}
