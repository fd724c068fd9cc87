/* The C API (kestrel/kestrel.h) used from plain C99, as a C flight firmware would: static storage,
 * init from a preset, a fixed-rate loop, motor commands, faults, a motor failure. The same
 * program runs on the host (ctest capi.host) and on the emulated Cortex-M4F (ctest
 * kestrel_capi_test under QEMU). Exit status 0 = every check passed.
 *
 * The loop is closed with a small rigid-body plant written here in C (semi-implicit Euler) for
 * the base quadrotor, whose geometry the test knows: rotors at (+-0.13, +-0.13) m, directions
 * [1, -1, 1, -1], reaction torque ratio 0.01 (allocation/presets.hpp), and with a second plant
 * that takes any kestrel_airframe (custom airframes, the X500, the hexarotor).
 *
 * Also checked (docs/capi.md): custom airframes (a hand-written X500 and base quadrotor give the
 * presets' outputs bit for bit; an asymmetric quad with tilted rotors and per-motor limits flies
 * to its setpoint), every validation rule at init and at step, clipping (KESTREL_CLIPPED, a
 * per-step condition and a latched fault), latched faults 0 in a normal flight, the PWM curve. */
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

/* A level vehicle at rest 1 m up, holding position (0, 0, 1) with yaw 0. */
static void level_hover_at_1m(kestrel_state* s, kestrel_setpoint* sp) {
  memset(s, 0, sizeof *s);
  s->position_w[2] = 1.0f;
  s->orientation_xyzw[3] = 1.0f;
  sp->mode = KESTREL_MODE_POSITION;
  sp->value[0] = 0.0f;
  sp->value[1] = 0.0f;
  sp->value[2] = 1.0f;
  sp->value[3] = 0.0f;
}

/* The kinematic part of a plant step, after v and w took this step's accelerations: position,
 * q += dt/2 q (x) (w, 0) normalised, and the ground. */
static void plant_advance(plant* b, float dt) {
  float x = b->q[0], y = b->q[1], z = b->q[2], w = b->q[3], n, qx, qy, qz, qw;
  int i;
  for (i = 0; i < 3; ++i) b->p[i] += b->v[i] * dt;
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

/* One step of the quadrotor plant with the motors' thrusts (N). */
static void plant_step(plant* b, const float* f, float dt) {
  static const float rx[4] = {0.13f, -0.13f, -0.13f, 0.13f};
  static const float ry[4] = {-0.13f, -0.13f, 0.13f, 0.13f};
  static const float dir[4] = {1.0f, -1.0f, 1.0f, -1.0f};
  const float m = 0.25f, jx = 0.000845f, jy = 0.000845f, jz = 0.00169f;
  float fz = 0.0f, tx = 0.0f, ty = 0.0f, tz = 0.0f;
  const float x = b->q[0], y = b->q[1], z = b->q[2], w = b->q[3];
  float ax, ay, az, dwx, dwy, dwz;
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
  plant_advance(b, dt);
}

/* Any airframe: force sum_i f_i a_i, torque sum_i p_i x f_i a_i - d_i ratio f_i a_i (a_i the
 * normalised axis), diagonal inertia j. */
static void plant_step_af(plant* b, const kestrel_airframe* af, float m, const float* j, const float* f, float dt) {
  float F[3] = {0.0f, 0.0f, 0.0f}, T[3] = {0.0f, 0.0f, 0.0f};
  const float x = b->q[0], y = b->q[1], z = b->q[2], w = b->q[3];
  float r[3][3], dw[3];
  int i, k;
  for (i = 0; i < af->num_rotors; ++i) {
    const kestrel_rotor* ro = &af->rotor[i];
    const float* p = ro->position_b_m;
    const float an = sqrtf_newton(ro->axis_b[0] * ro->axis_b[0] + ro->axis_b[1] * ro->axis_b[1] + ro->axis_b[2] * ro->axis_b[2]);
    float a[3], fa[3];
    for (k = 0; k < 3; ++k) {
      a[k] = ro->axis_b[k] / an;
      fa[k] = f[i] * a[k];
      F[k] += fa[k];
      T[k] -= (float)ro->direction * af->torque_to_thrust_m * fa[k];
    }
    T[0] += p[1] * fa[2] - p[2] * fa[1];
    T[1] += p[2] * fa[0] - p[0] * fa[2];
    T[2] += p[0] * fa[1] - p[1] * fa[0];
  }
  r[0][0] = 1.0f - 2.0f * (y * y + z * z);
  r[0][1] = 2.0f * (x * y - w * z);
  r[0][2] = 2.0f * (x * z + w * y);
  r[1][0] = 2.0f * (x * y + w * z);
  r[1][1] = 1.0f - 2.0f * (x * x + z * z);
  r[1][2] = 2.0f * (y * z - w * x);
  r[2][0] = 2.0f * (x * z - w * y);
  r[2][1] = 2.0f * (y * z + w * x);
  r[2][2] = 1.0f - 2.0f * (x * x + y * y);
  for (k = 0; k < 3; ++k) b->v[k] += (r[k][0] * F[0] + r[k][1] * F[1] + r[k][2] * F[2]) / m * dt;
  b->v[2] -= 9.81f * dt;
  dw[0] = (T[0] - (j[2] - j[1]) * b->w[1] * b->w[2]) / j[0];
  dw[1] = (T[1] - (j[0] - j[2]) * b->w[2] * b->w[0]) / j[1];
  dw[2] = (T[2] - (j[1] - j[0]) * b->w[0] * b->w[1]) / j[2];
  for (k = 0; k < 3; ++k) b->w[k] += dw[k] * dt;
  plant_advance(b, dt);
}

/* Every output field but the padding, bit for bit. */
static int outputs_identical(const kestrel_output* a, const kestrel_output* b) {
  return a->num_motors == b->num_motors && memcmp(a->motor_command, b->motor_command, sizeof a->motor_command) == 0 &&
         memcmp(a->thrust_setpoint_N, b->thrust_setpoint_N, sizeof a->thrust_setpoint_N) == 0 &&
         memcmp(a->thrust_N, b->thrust_N, sizeof a->thrust_N) == 0 &&
         memcmp(a->wrench_b, b->wrench_b, sizeof a->wrench_b) == 0 && a->faults == b->faults &&
         a->saturated_mask == b->saturated_mask && a->conditions == b->conditions;
}

static void set_rotor(kestrel_airframe* af, int i, float x, float y, float z, float ax, float ay, float az, int dir,
                      float lo, float hi) {
  kestrel_rotor* r = &af->rotor[i];
  r->position_b_m[0] = x;
  r->position_b_m[1] = y;
  r->position_b_m[2] = z;
  r->axis_b[0] = ax;
  r->axis_b[1] = ay;
  r->axis_b[2] = az;
  r->direction = dir;
  r->thrust_min_N = lo;
  r->thrust_max_N = hi;
}

/* The X500 written out by hand from its data sheet numbers (PX4 motor order, kestrel.h's picture). */
static void x500_by_hand(kestrel_airframe* af) {
  memset(af, 0, sizeof *af);
  af->num_rotors = 4;
  set_rotor(af, 0, 0.175f, -0.175f, 0.0f, 0.0f, 0.0f, 1.0f, 1, 0.0f, 10.0f);  /* front-right CCW */
  set_rotor(af, 1, -0.175f, 0.175f, 0.0f, 0.0f, 0.0f, 1.0f, 1, 0.0f, 10.0f);  /* rear-left CCW */
  set_rotor(af, 2, 0.175f, 0.175f, 0.0f, 0.0f, 0.0f, 1.0f, -1, 0.0f, 10.0f);  /* front-left CW */
  set_rotor(af, 3, -0.175f, -0.175f, 0.0f, 0.0f, 0.0f, 1.0f, -1, 0.0f, 10.0f); /* rear-right CW */
  af->torque_to_thrust_m = 0.016f;
  af->thrust_constant = 8.54858e-6f;
  af->time_constant_up_s = 0.0125f;
  af->time_constant_down_s = 0.025f;
}

static void base_quad_by_hand(kestrel_airframe* af) {
  memset(af, 0, sizeof *af);
  af->num_rotors = 4;
  set_rotor(af, 0, 0.13f, -0.13f, 0.0f, 0.0f, 0.0f, 1.0f, 1, 0.0f, 2.0f);  /* front-right CCW */
  set_rotor(af, 1, -0.13f, -0.13f, 0.0f, 0.0f, 0.0f, 1.0f, -1, 0.0f, 2.0f); /* rear-right CW */
  set_rotor(af, 2, -0.13f, 0.13f, 0.0f, 0.0f, 0.0f, 1.0f, 1, 0.0f, 2.0f);  /* rear-left CCW */
  set_rotor(af, 3, 0.13f, 0.13f, 0.0f, 0.0f, 0.0f, 1.0f, -1, 0.0f, 2.0f);  /* front-left CW */
  af->torque_to_thrust_m = 0.01f;
  af->thrust_constant = 0.0f;
  af->time_constant_up_s = 0.04f;
  af->time_constant_down_s = 0.04f;
}

static kestrel_storage g_custom;
static kestrel_storage g_preset;

/* Flies the preset stack and the custom stack side by side from the ground to `target` (n steps at
 * 500 Hz) in the plant of `af`; returns the final position error (m). *identical: every step's
 * status and outputs were the same bits; *all_ok: every status KESTREL_OK. */
static float fly_pair(kestrel_storage* a, kestrel_storage* b, const kestrel_airframe* af, const kestrel_params* p,
                      const float* target, int steps, int* identical, int* all_ok, kestrel_output* last) {
  plant pl;
  kestrel_state s;
  kestrel_setpoint sp;
  kestrel_output oa, ob;
  float e0, e1, e2;
  int k, i;
  memset(&pl, 0, sizeof pl);
  pl.q[3] = 1.0f;
  sp.mode = KESTREL_MODE_POSITION;
  for (i = 0; i < 4; ++i) sp.value[i] = target[i];
  *identical = 1;
  *all_ok = 1;
  memset(&oa, 0, sizeof oa);
  memset(&ob, 0, sizeof ob);
  for (k = 0; k < steps; ++k) {
    kestrel_status sa, sb = KESTREL_OK;
    plant_to_state(&pl, &s);
    sa = kestrel_step(a, &s, &sp, 0.002f, &oa);
    if (b != NULL) {
      sb = kestrel_step(b, &s, &sp, 0.002f, &ob);
      if (sa != sb || !outputs_identical(&oa, &ob)) *identical = 0;
    }
    if (sa != KESTREL_OK) *all_ok = 0;
    for (i = 0; i < oa.num_motors; ++i) {
      if (!(oa.motor_command[i] >= 0.0f && oa.motor_command[i] <= 1.0f)) *all_ok = 0;
    }
    plant_step_af(&pl, af, p->mass_kg, p->inertia_diag_kgm2, oa.thrust_N, 0.002f);
  }
  *last = oa;
  e0 = pl.p[0] - target[0];
  e1 = pl.p[1] - target[1];
  e2 = pl.p[2] - target[2];
  return sqrtf_newton(e0 * e0 + e1 * e1 + e2 * e2);
}

static void print_err(const char* what, float err) {
  capi_test_print("  ");
  capi_test_print(what);
  capi_test_print(": final position error ");
  capi_test_print_fixed((double)err * 1000.0, 2);
  capi_test_print(" mm\n");
}

/* Custom airframes equal to a preset give the preset's bits. */
static void test_custom_equals_preset(void) {
  static const float target[4] = {0.5f, -0.3f, 1.2f, 0.3f};
  kestrel_airframe hand, from;
  kestrel_params p;
  kestrel_output last;
  int identical, all_ok;
  float err;

  /* X500 with its motor model (rotor-speed state, PX4 time constants). */
  x500_by_hand(&hand);
  memset(&from, 0, sizeof from);
  check(kestrel_airframe_from_preset(KESTREL_PRESET_X500, &from) == KESTREL_OK, "x500 airframe from preset");
  check(memcmp(&hand, &from, sizeof hand) == 0, "x500 by hand = kestrel_airframe_from_preset (motor order, directions, constants)");
  check(kestrel_default_params(KESTREL_PRESET_X500, &p) == KESTREL_OK, "x500 params");
  check(kestrel_init(&g_preset, KESTREL_PRESET_X500) == KESTREL_OK, "x500 preset init");
  check(kestrel_init_airframe(&g_custom, &hand, &p) == KESTREL_OK, "x500 by hand init");
  err = fly_pair(&g_preset, &g_custom, &hand, &p, target, 4000, &identical, &all_ok, &last);
  print_err("x500 by hand beside the preset", err);
  check(identical, "x500 by hand: bit-identical to the preset on every step");
  check(all_ok, "x500: every step OK, commands in [0, 1]");
  check(err < 0.05f, "x500 reaches the setpoint within 5 cm");
  check(last.faults == 0u && kestrel_faults(&g_custom) == 0u, "x500: no latched fault after take-off and flight");

  /* Hexarotor from the preset's data, motor model on. */
  check(kestrel_airframe_from_preset(KESTREL_PRESET_HEXAROTOR, &from) == KESTREL_OK, "hexa airframe from preset");
  check(from.num_rotors == 6 && from.rotor[2].position_b_m[1] == 0.25f && from.rotor[2].direction == 1 &&
            from.rotor[5].direction == -1 && from.rotor[0].position_b_m[0] > 0.2f && from.rotor[0].position_b_m[1] < 0.0f,
        "hexa motor order: 0 front-right, 2 left CCW, 5 right CW");
  check(kestrel_default_params(KESTREL_PRESET_HEXAROTOR, &p) == KESTREL_OK, "hexa params");
  check(kestrel_init(&g_preset, KESTREL_PRESET_HEXAROTOR) == KESTREL_OK, "hexa preset init");
  check(kestrel_init_airframe(&g_custom, &from, &p) == KESTREL_OK, "hexa airframe init");
  err = fly_pair(&g_preset, &g_custom, &from, &p, target, 4000, &identical, &all_ok, &last);
  print_err("hexarotor airframe beside the preset", err);
  check(identical, "hexa airframe: bit-identical to the preset on every step");
  check(err < 0.05f, "hexa reaches the setpoint within 5 cm");
  check(last.num_motors == 6, "hexa: 6 motors");

  /* Base quadrotor by hand, motor model off (its preset's motor model is Aerial Gym's own). */
  base_quad_by_hand(&hand);
  check(kestrel_airframe_from_preset(KESTREL_PRESET_BASE_QUADROTOR, &from) == KESTREL_OK, "quad airframe from preset");
  check(memcmp(hand.rotor, from.rotor, sizeof hand.rotor) == 0 && from.torque_to_thrust_m == 0.01f,
        "base quad by hand = kestrel_airframe_from_preset geometry");
  check(kestrel_default_params(KESTREL_PRESET_BASE_QUADROTOR, &p) == KESTREL_OK, "quad params");
  p.use_motor_model = 0;
  check(kestrel_init_params(&g_preset, &p) == KESTREL_OK, "quad preset init (no motor model)");
  check(kestrel_init_airframe(&g_custom, &hand, &p) == KESTREL_OK, "quad by hand init (no motor model)");
  err = fly_pair(&g_preset, &g_custom, &hand, &p, target, 4000, &identical, &all_ok, &last);
  print_err("base quad by hand beside the preset", err);
  check(identical, "base quad by hand: bit-identical to the preset on every step");
  check(err < 0.05f, "base quad by hand reaches the setpoint within 5 cm");
}

/* An asymmetric quad: long front arms, short rear arms, rotors tilted 5 deg outward (axes given
 * unnormalised), per-motor limits (front [0, 6] N, rear [0.2, 7] N), thrust-state motor model. */
static void test_asymmetric_quad(void) {
  static const float target[4] = {0.5f, -0.3f, 1.5f, 0.3f};
  kestrel_airframe af;
  kestrel_params p;
  kestrel_output last;
  int identical, all_ok, i;
  float err;
  memset(&af, 0, sizeof af);
  af.num_rotors = 4;
  set_rotor(&af, 0, 0.15f, -0.12f, 0.01f, 0.0f, -0.0875f, 1.0f, 1, 0.0f, 6.0f);  /* front-right CCW */
  set_rotor(&af, 1, -0.10f, 0.09f, 0.01f, 0.0f, 0.0875f, 1.0f, 1, 0.2f, 7.0f);   /* rear-left CCW */
  set_rotor(&af, 2, 0.15f, 0.12f, 0.01f, 0.0f, 0.0875f, 1.0f, -1, 0.0f, 6.0f);   /* front-left CW */
  set_rotor(&af, 3, -0.10f, -0.09f, 0.01f, 0.0f, -0.0875f, 1.0f, -1, 0.2f, 7.0f); /* rear-right CW */
  af.torque_to_thrust_m = 0.016f;
  af.thrust_constant = 0.0f;
  af.time_constant_up_s = 0.02f;
  af.time_constant_down_s = 0.03f;
  check(kestrel_default_params(KESTREL_PRESET_X500, &p) == KESTREL_OK, "asym: params");
  p.mass_kg = 1.5f;
  p.inertia_diag_kgm2[0] = 0.012f;
  p.inertia_diag_kgm2[1] = 0.015f;
  p.inertia_diag_kgm2[2] = 0.025f;
  check(kestrel_init_airframe(&g_custom, &af, &p) == KESTREL_OK, "asym: init");
  err = fly_pair(&g_custom, NULL, &af, &p, target, 4000, &identical, &all_ok, &last);
  print_err("asymmetric tilted quad (custom)", err);
  capi_test_print("    hover thrusts");
  for (i = 0; i < 4; ++i) {
    capi_test_print(" ");
    capi_test_print_fixed((double)last.thrust_setpoint_N[i], 3);
  }
  capi_test_print(" N\n");
  check(err < 0.05f, "asym quad reaches the setpoint within 5 cm");
  check(all_ok, "asym quad: every step OK, commands in [0, 1]");
  check(last.faults == 0u, "asym quad: no latched fault after take-off and flight");
  /* At hover the short rear arms carry more: 0.15 f_front = 0.10 f_rear. */
  check(last.thrust_setpoint_N[1] > 1.3f * last.thrust_setpoint_N[0] && last.thrust_setpoint_N[3] > 1.3f * last.thrust_setpoint_N[2],
        "asym quad: rear motors carry ~1.5x the front's");
  /* motor_command is the fraction of each motor's own range. */
  check(absf(last.motor_command[1] - (last.thrust_setpoint_N[1] - 0.2f) / 6.8f) < 1e-5f &&
            absf(last.motor_command[0] - last.thrust_setpoint_N[0] / 6.0f) < 1e-5f,
        "asym quad: motor_command normalised to each motor's range");
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

static volatile float g_zero = 0.0f; /* NaN = g_zero / g_zero at run time, without <math.h> */

/* The validation rules of kestrel.h / docs/capi.md: what init refuses (with which status), what
 * step refuses, and that a refusal leaves the storage unusable and `out` untouched. */
static void test_validation(void) {
  kestrel_params p, x500;
  kestrel_airframe af;
  kestrel_state s;
  kestrel_setpoint sp;
  kestrel_output out, before;
  int i;
  level_hover_at_1m(&s, &sp);
  memset(&before, 0x5a, sizeof before);

  /* Negative gains: INVALID_ARGUMENT, and a storage that held a working stack is unusable. */
  check(kestrel_default_params(KESTREL_PRESET_X500, &x500) == KESTREL_OK, "v: x500 params");
  for (i = 0; i < 4; ++i) {
    p = x500;
    if (i == 0) p.k_pos[0] = -1.0f;
    if (i == 1) p.k_vel[2] = -0.5f;
    if (i == 2) p.k_rot[1] = -1.0f;
    if (i == 3) p.k_angvel[0] = -1e-3f;
    check(kestrel_init(&g_custom, KESTREL_PRESET_X500) == KESTREL_OK, "v: init before the refused one");
    check(kestrel_init_params(&g_custom, &p) == KESTREL_INVALID_ARGUMENT, "v: negative gain refused (INVALID_ARGUMENT)");
    out = before;
    check(kestrel_step(&g_custom, &s, &sp, 0.002f, &out) == KESTREL_INVALID_ARGUMENT, "v: refused init leaves the storage unusable");
    check(memcmp(&out, &before, sizeof out) == 0, "v: step on an unusable storage leaves out unchanged");
  }
  p = x500;
  p.inertia_diag_kgm2[2] = 0.0f;
  check(kestrel_init_params(&g_custom, &p) == KESTREL_INVALID_ARGUMENT, "v: zero inertia refused");
  p = x500;
  p.yaw_headroom = -0.1f;
  check(kestrel_init_params(&g_custom, &p) == KESTREL_INVALID_ARGUMENT, "v: negative yaw headroom refused");
  p = x500;
  p.mass_kg = g_zero / g_zero;
  check(kestrel_init_params(&g_custom, &p) == KESTREL_INVALID_ARGUMENT, "v: NaN mass refused");

  /* Thrust-to-weight: the X500's 4 x 10 N lift 40 / 9.81 = 4.08 kg at most. */
  p = x500;
  p.mass_kg = 50.0f;
  check(kestrel_init_params(&g_custom, &p) == KESTREL_INSUFFICIENT_THRUST, "v: 50 kg on the X500 refused (INSUFFICIENT_THRUST)");
  check(kestrel_step(&g_custom, &s, &sp, 0.002f, &out) == KESTREL_INVALID_ARGUMENT, "v: 50 kg X500 storage unusable");
  p.mass_kg = 4.1f;
  check(kestrel_init_params(&g_custom, &p) == KESTREL_INSUFFICIENT_THRUST, "v: 4.1 kg X500 (T/W 0.995) refused");
  p.mass_kg = 4.0f;
  check(kestrel_init_params(&g_custom, &p) == KESTREL_OK, "v: 4.0 kg X500 (T/W 1.02) accepted");

  /* Step: non-unit quaternion, dt = 1e9 s. */
  check(kestrel_init(&g_custom, KESTREL_PRESET_X500) == KESTREL_OK, "v: x500 init");
  out = before;
  s.orientation_xyzw[3] = 0.0f;
  check(kestrel_step(&g_custom, &s, &sp, 0.002f, &out) == KESTREL_INVALID_ARGUMENT, "v: zero quaternion refused");
  s.orientation_xyzw[3] = 0.9f;
  check(kestrel_step(&g_custom, &s, &sp, 0.002f, &out) == KESTREL_INVALID_ARGUMENT, "v: |q| = 0.9 refused");
  s.orientation_xyzw[3] = 1.0f;
  check(kestrel_step(&g_custom, &s, &sp, 1e9f, &out) == KESTREL_INVALID_ARGUMENT, "v: dt = 1e9 s refused");
  check(kestrel_step(&g_custom, &s, &sp, g_zero / g_zero, &out) == KESTREL_INVALID_ARGUMENT, "v: dt = NaN refused");
  check(kestrel_step(&g_custom, &s, &sp, -0.002f, &out) == KESTREL_INVALID_ARGUMENT, "v: negative dt refused");
  check(memcmp(&out, &before, sizeof out) == 0, "v: refused steps leave out unchanged");
  check(kestrel_step(&g_custom, &s, &sp, 0.002f, &out) == KESTREL_OK, "v: the stack still steps after refused steps");

  /* Custom airframe rules (INVALID_ARGUMENT), then geometry (SINGULAR) and lift (INSUFFICIENT_THRUST). */
  x500_by_hand(&af);
  check(kestrel_init_airframe(&g_custom, &af, &x500) == KESTREL_OK, "v: x500 airframe accepted");
  af.num_rotors = 0;
  check(kestrel_init_airframe(&g_custom, &af, &x500) == KESTREL_INVALID_ARGUMENT, "v: 0 rotors refused");
  af.num_rotors = KESTREL_MAX_MOTORS + 1;
  check(kestrel_init_airframe(&g_custom, &af, &x500) == KESTREL_INVALID_ARGUMENT, "v: 13 rotors refused");
  x500_by_hand(&af);
  af.rotor[2].direction = 0;
  check(kestrel_init_airframe(&g_custom, &af, &x500) == KESTREL_INVALID_ARGUMENT, "v: direction 0 refused");
  x500_by_hand(&af);
  af.rotor[1].axis_b[2] = 0.0f;
  check(kestrel_init_airframe(&g_custom, &af, &x500) == KESTREL_INVALID_ARGUMENT, "v: zero axis refused");
  x500_by_hand(&af);
  af.rotor[3].thrust_min_N = 10.0f;
  check(kestrel_init_airframe(&g_custom, &af, &x500) == KESTREL_INVALID_ARGUMENT, "v: min = max thrust refused");
  x500_by_hand(&af);
  af.rotor[0].position_b_m[0] = g_zero / g_zero;
  check(kestrel_init_airframe(&g_custom, &af, &x500) == KESTREL_INVALID_ARGUMENT, "v: NaN rotor position refused");
  x500_by_hand(&af);
  af.rotor[0].thrust_min_N = -1.0f;
  check(kestrel_init_airframe(&g_custom, &af, &x500) == KESTREL_INVALID_ARGUMENT, "v: negative thrust with the rotor-speed model refused");
  af.thrust_constant = 0.0f; /* the thrust-state model allows reversible motors */
  check(kestrel_init_airframe(&g_custom, &af, &x500) == KESTREL_OK, "v: negative thrust with the thrust-state model accepted");
  x500_by_hand(&af);
  af.time_constant_up_s = 0.0f;
  check(kestrel_init_airframe(&g_custom, &af, &x500) == KESTREL_INVALID_ARGUMENT, "v: zero time constant refused");
  p = x500;
  p.use_motor_model = 0;
  check(kestrel_init_airframe(&g_custom, &af, &p) == KESTREL_OK, "v: time constants ignored without the motor model");
  x500_by_hand(&af);
  af.torque_to_thrust_m = -0.016f;
  check(kestrel_init_airframe(&g_custom, &af, &x500) == KESTREL_INVALID_ARGUMENT, "v: negative torque ratio refused");
  x500_by_hand(&af);
  for (i = 0; i < 4; ++i) af.rotor[i].position_b_m[1] = 0.0f; /* all rotors on the x axis: no roll torque */
  check(kestrel_init_airframe(&g_custom, &af, &x500) == KESTREL_SINGULAR, "v: rotors on one line refused (SINGULAR)");
  check(kestrel_step(&g_custom, &s, &sp, 0.002f, &out) == KESTREL_INVALID_ARGUMENT, "v: SINGULAR init leaves it unusable");
  x500_by_hand(&af);
  for (i = 0; i < 4; ++i) af.rotor[i].axis_b[2] = -1.0f; /* every rotor pushes down */
  check(kestrel_init_airframe(&g_custom, &af, &x500) == KESTREL_INSUFFICIENT_THRUST, "v: downward rotors refused (INSUFFICIENT_THRUST)");
  check(kestrel_airframe_from_preset(99, &af) == KESTREL_INVALID_ARGUMENT, "v: unknown preset airframe refused");
}

/* A 1e6 m setpoint: clipped to KESTREL_SETPOINT_MAX, KESTREL_CLIPPED, flagged in the step's
 * conditions and latched; the output is exactly the one for the clipped setpoint. */
static void test_clipping(void) {
  kestrel_state s;
  kestrel_setpoint sp, sp10;
  kestrel_output o, o10;
  int i, sane = 1;
  memset(&s, 0, sizeof s);
  s.position_w[2] = 1.0f;
  s.orientation_xyzw[3] = 1.0f;
  sp.mode = KESTREL_MODE_POSITION;
  sp.value[0] = 1e6f;
  sp.value[1] = 0.0f;
  sp.value[2] = 1.0f;
  sp.value[3] = 0.0f;
  sp10 = sp;
  sp10.value[0] = KESTREL_SETPOINT_MAX;
  check(kestrel_init(&g_custom, KESTREL_PRESET_X500) == KESTREL_OK, "clip: init");
  check(kestrel_init(&g_preset, KESTREL_PRESET_X500) == KESTREL_OK, "clip: init twin");
  check(kestrel_step(&g_custom, &s, &sp, 0.002f, &o) == KESTREL_CLIPPED, "clip: 1e6 m setpoint -> KESTREL_CLIPPED");
  check(kestrel_step(&g_preset, &s, &sp10, 0.002f, &o10) == KESTREL_OK, "clip: a setpoint at the bound is OK");
  check((o.conditions & KESTREL_FAULT_COMMAND_OUT_OF_RANGE) != 0u, "clip: out-of-range in this step's conditions");
  check((o.faults & KESTREL_FAULT_COMMAND_OUT_OF_RANGE) != 0u, "clip: out-of-range latched");
  check(memcmp(o.motor_command, o10.motor_command, sizeof o.motor_command) == 0 &&
            memcmp(o.wrench_b, o10.wrench_b, sizeof o.wrench_b) == 0,
        "clip: output = the output for the setpoint clipped to 10 m");
  for (i = 0; i < o.num_motors; ++i) sane = sane && o.motor_command[i] >= 0.0f && o.motor_command[i] <= 1.0f;
  check(sane, "clip: commands in [0, 1]");
  check(o.wrench_b[4] > 0.0f, "clip: pitches toward +x (positive torque about +y (left): nose down)");
  sp.value[0] = 0.0f;
  check(kestrel_step(&g_custom, &s, &sp, 0.002f, &o) == KESTREL_OK, "clip: in-range setpoint -> OK again");
  check((o.conditions & KESTREL_FAULT_COMMAND_OUT_OF_RANGE) == 0u, "clip: the condition is per step");
  check(o.faults == KESTREL_FAULT_COMMAND_OUT_OF_RANGE && kestrel_faults(&g_custom) == KESTREL_FAULT_COMMAND_OUT_OF_RANGE,
        "clip: the fault stays latched");
  kestrel_clear_faults(&g_custom);
  check(kestrel_step(&g_custom, &s, &sp, 0.002f, &o) == KESTREL_OK && o.faults == 0u, "clip: cleared");
  /* Other modes clip the same way: a 50 rad/s rate command. */
  sp.mode = KESTREL_MODE_RATES;
  sp.value[0] = 0.0f;
  sp.value[1] = 50.0f;
  check(kestrel_step(&g_custom, &s, &sp, 0.002f, &o) == KESTREL_CLIPPED, "clip: 50 rad/s rate -> KESTREL_CLIPPED");
}

/* The thrust curve: PX4's THR_MDL_FAC model inverted. */
static void test_pwm_curve(void) {
  static const float ks[4] = {0.0f, 0.3f, 0.7f, 1.0f};
  int i, j, inverse_ok = 1, monotonic = 1;
  check(kestrel_command_to_throttle(0.25f, 0.0f) == 0.25f, "pwm: k = 0 is linear");
  check(absf(kestrel_command_to_throttle(0.25f, 1.0f) - 0.5f) < 1e-6f, "pwm: k = 1, a quarter of the thrust is half throttle");
  check(absf(kestrel_command_to_throttle(0.5f, 1.0f) - 0.70710678f) < 1e-6f, "pwm: k = 1, half thrust is 70.7 % throttle");
  check(absf(kestrel_command_to_throttle(0.5f, 0.5f) - 0.61803399f) < 1e-6f, "pwm: k = 0.5, half thrust is 61.8 % (u^2 + u = 1)");
  check(kestrel_command_to_throttle(0.0f, 1.0f) == 0.0f && kestrel_command_to_throttle(-1.0f, 0.5f) == 0.0f, "pwm: zero and below -> 0");
  check(kestrel_command_to_throttle(g_zero / g_zero, 0.5f) == 0.0f, "pwm: NaN command -> 0 (idle)");
  check(absf(kestrel_command_to_throttle(0.5f, g_zero / g_zero) - 0.5f) < 1e-6f, "pwm: NaN k -> linear");
  check(absf(kestrel_command_to_throttle(0.5f, 3.0f) - 0.70710678f) < 1e-6f, "pwm: k clamped to 1");
  for (j = 0; j < 4; ++j) {
    float prev = -1.0f;
    check(kestrel_command_to_throttle(1.0f, ks[j]) == 1.0f && kestrel_command_to_throttle(2.0f, ks[j]) == 1.0f, "pwm: full thrust is full throttle");
    for (i = 0; i <= 100; ++i) {
      const float t = (float)i / 100.0f;
      const float u = kestrel_command_to_throttle(t, ks[j]);
      const float back = (1.0f - ks[j]) * u + ks[j] * u * u;
      if (absf(back - t) > 2e-6f) inverse_ok = 0;
      if (!(u >= prev)) monotonic = 0;
      prev = u;
    }
  }
  check(inverse_ok, "pwm: (1 - k) u + k u^2 gives the command back (k 0, 0.3, 0.7, 1)");
  check(monotonic, "pwm: throttle monotonic in the command");
  check(absf(kestrel_thrust_to_pwm_us(0.25f, 1.0f, 1000.0f, 2000.0f) - 1500.0f) < 1e-3f, "pwm: k = 1, 0.25 -> 1500 us");
  check(absf(kestrel_thrust_to_pwm_us(0.5f, 0.5f, 1000.0f, 2000.0f) - 1618.034f) < 2e-3f, "pwm: k = 0.5, 0.5 -> 1618.03 us");
  check(kestrel_thrust_to_pwm_us(0.0f, 0.5f, 1000.0f, 2000.0f) == 1000.0f, "pwm: 0 -> min_us");
  check(kestrel_thrust_to_pwm_us(1.0f, 0.5f, 1000.0f, 2000.0f) == 2000.0f, "pwm: 1 -> max_us");
  check(absf(kestrel_command_to_pwm_us(0.25f, 1000.0f, 2000.0f) - 1250.0f) < 1e-3f, "pwm: the deprecated map stays linear");
  capi_test_print("  PWM at half thrust (1000..2000 us): linear ");
  capi_test_print_fixed((double)kestrel_command_to_pwm_us(0.5f, 1000.0f, 2000.0f), 1);
  capi_test_print(", THR_MDL_FAC 0.5 ");
  capi_test_print_fixed((double)kestrel_thrust_to_pwm_us(0.5f, 0.5f, 1000.0f, 2000.0f), 1);
  capi_test_print(", thrust ~ throttle^2 ");
  capi_test_print_fixed((double)kestrel_thrust_to_pwm_us(0.5f, 1.0f, 1000.0f, 2000.0f), 1);
  capi_test_print(" us\n");
}

/* Take off to 1 m, then fly to (0.5, -0.3, 1.2) with yaw 0.3; 8 s at 500 Hz. */
static void test_closed_loop_quad(void) {
  const float dt = 0.002f;
  plant b;
  kestrel_state s;
  kestrel_setpoint sp;
  kestrel_output out, out_twin;
  float err = 0.0f, e0, e1, e2;
  int k, in_range = 1, identical = 1, saturated_steps = 0, faults_after_takeoff = 0;
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
    if ((out.conditions & KESTREL_FAULT_SATURATED) != 0u) ++saturated_steps;
    if (out.faults != 0u) ++faults_after_takeoff;
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
  capi_test_print("  quad: steps with the saturated condition ");
  capi_test_print_int((long)saturated_steps);
  capi_test_print(", steps with a latched fault ");
  capi_test_print_int((long)faults_after_takeoff);
  capi_test_print("\n");
  check(saturated_steps > 0, "take-off saturates (a per-step condition)");
  check(faults_after_takeoff == 0 && kestrel_faults(&g_quad) == 0u, "normal flight: latched faults 0 on every step");
  check((out.conditions & KESTREL_FAULT_SATURATED) == 0u && out.saturated_mask == 0u, "hover: no saturation condition");
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
  level_hover_at_1m(&s, &sp);
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
  test_custom_equals_preset();
  test_asymmetric_quad();
  test_validation();
  test_clipping();
  test_pwm_curve();
  capi_test_print("  storage used ");
  capi_test_print_int((long)kestrel_storage_used());
  capi_test_print(" of ");
  capi_test_print_int((long)KESTREL_STORAGE_BYTES);
  capi_test_print(" bytes\n");
  capi_test_print(g_failures == 0 ? "capi: PASS\n" : "capi: FAIL\n");
  return g_failures == 0 ? 0 : 1;
}
