/* Kestrel C API: the multirotor control stack (Lee controller -> sequential-desaturation
 * allocation -> first-order motor model) behind a plain C99 interface, for C flight firmware
 * (Crazyflie-, Betaflight-style) and any language with a C FFI.
 *
 * Why a C layer: firmware main loops, schedulers and HALs of the open flight stacks are C; they
 * call a controller as a function over an explicit struct (Crazyflie's controllerLee(...)). This
 * header is that function table for the Kestrel core; it includes no C++ and allocates nothing.
 *
 * Memory: the caller owns the storage (static, stack or a pool), a kestrel_storage of
 * KESTREL_STORAGE_BYTES aligned for any scalar. The C++ side checks with static_assert that the
 * stack fits. There is no heap, no global state: two storages are two independent vehicles.
 *
 * Units and frames (as in the C++ core, docs/design.md in the repository): SI, world frame z up,
 * body frame x forward / y left / z up, quaternions xyzw (scalar last) rotating body vectors into
 * the world, wrench [fx fy fz tx ty tz] in the body frame.
 *
 * Scalars are float here; a core built with KESTREL_DOUBLE converts at the boundary.
 */
#ifndef KESTREL_KESTREL_H
#define KESTREL_KESTREL_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Bytes of caller-provided storage one control stack needs (float and double cores). */
#if defined(KESTREL_USE_DOUBLE) && KESTREL_USE_DOUBLE
#define KESTREL_STORAGE_BYTES 8192u
#else
#define KESTREL_STORAGE_BYTES 4096u
#endif
#define KESTREL_MAX_MOTORS 12

/* Opaque, suitably aligned storage. Never read or write its bytes. */
typedef struct kestrel_storage {
  union {
    unsigned char bytes[KESTREL_STORAGE_BYTES];
    double align_double;
    uint64_t align_u64;
    void* align_ptr;
  } u;
} kestrel_storage;

/* Status codes (values of the C++ kestrel::Status). */
typedef enum kestrel_status {
  KESTREL_OK = 0,
  KESTREL_INVALID_ARGUMENT = 1, /* a parameter outside its documented range; nothing changed */
  KESTREL_NON_FINITE_INPUT = 2, /* NaN/inf in an input: the last safe output was held */
  KESTREL_CAPACITY_EXCEEDED = 3,
  KESTREL_SINGULAR = 4,
  KESTREL_NOT_CONVERGED = 5,
  KESTREL_NON_FINITE_OUTPUT = 6 /* finite inputs overflowed inside a stage (absurd magnitudes): the last
                                   finite output was held, KESTREL_FAULT_NON_FINITE_OUTPUT latched */
} kestrel_status;

/* Largest control period kestrel_step() accepts (s). Larger steps make no sense for a control loop
 * and overflow the motor model (around 1e16 s); they are refused with KESTREL_INVALID_ARGUMENT. */
#define KESTREL_MAX_DT_S 1.0f

/* kestrel_state.orientation_xyzw must be a unit quaternion within this tolerance:
 * | |q| - 1 | <= KESTREL_QUAT_NORM_TOLERANCE, else kestrel_step() returns KESTREL_INVALID_ARGUMENT
 * (a zero or unnormalised quaternion gives a meaningless rotation). An estimator that renormalises
 * each update is far inside it. A NaN/inf component is a non-finite input instead (held output,
 * KESTREL_NON_FINITE_INPUT). */
#define KESTREL_QUAT_NORM_TOLERANCE 1e-3f

/* Fault bits (values of the C++ kestrel::Fault), latched until kestrel_clear_faults(). */
#define KESTREL_FAULT_NON_FINITE_COMMAND 0x001u
#define KESTREL_FAULT_NON_FINITE_STATE 0x002u
#define KESTREL_FAULT_COMMAND_OUT_OF_RANGE 0x004u
#define KESTREL_FAULT_SATURATED 0x008u
#define KESTREL_FAULT_SINGULAR 0x010u
#define KESTREL_FAULT_UNALLOCATED 0x020u
#define KESTREL_FAULT_MOTOR_FAILURE 0x040u
#define KESTREL_FAULT_NOT_CONVERGED 0x080u
#define KESTREL_FAULT_NON_FINITE_OUTPUT 0x100u

/* Airframe presets (ids of kestrel::allocation::AirframePreset that the C API supports). */
typedef enum kestrel_preset {
  KESTREL_PRESET_BASE_QUADROTOR = 0, /* Aerial Gym's 0.25 kg quad, [0, 2] N per motor */
  KESTREL_PRESET_HEXAROTOR = 4,      /* 2.4 kg flat hex-X, [0, 8] N per motor */
  KESTREL_PRESET_X500 = 5            /* Holybro X500 class quad, 2.0 kg, [0, 10] N per motor */
} kestrel_preset;

/* What the setpoint's four values mean (Aerial Gym's controller registry, kestrel::ControllerKind). */
typedef enum kestrel_mode {
  KESTREL_MODE_POSITION = 0, /* [x_w, y_w, z_w, yaw] m, m, m, rad */
  KESTREL_MODE_VELOCITY = 1, /* [vx_v, vy_v, vz_v, yaw_rate] m/s in the yaw frame, rad/s */
  KESTREL_MODE_ATTITUDE = 3, /* [thrust, roll, pitch, yaw_rate]: fz = (thrust + 1) m g */
  KESTREL_MODE_RATES = 4     /* [thrust, p, q, r] body rates rad/s */
} kestrel_mode;

/* Everything kestrel_init_params() reads: plain data with documented defaults
 * (kestrel_default_params() fills them from a preset). */
typedef struct kestrel_params {
  int32_t preset;             /* kestrel_preset: airframe geometry, motor limits and motor model */
  float mass_kg;              /* (0, 1e6] */
  float inertia_diag_kgm2[3]; /* body-axis principal moments, |J| <= 1e6 */
  float k_pos[3];             /* (m/s^2) per m; every gain |k| <= 1e6 (kestrel::kLeeMaxGain) */
  float k_vel[3];             /* (m/s^2) per m/s */
  float k_rot[3];             /* N m per unit attitude error */
  float k_angvel[3];          /* N m per rad/s */
  float max_yaw_rate_radps;   /* >= 0 */
  float yaw_headroom;         /* desaturation: fraction of the range yaw may exceed max by (PX4: 0.15) */
  int32_t use_motor_model;    /* 1: step the motor model (predicted thrust in out->thrust_N) */
} kestrel_params;

/* The vehicle state estimate the controller reads. */
typedef struct kestrel_state {
  float position_w[3];       /* m */
  float orientation_xyzw[4]; /* unit quaternion (KESTREL_QUAT_NORM_TOLERANCE), body -> world */
  float linvel_w[3];         /* m/s */
  float angvel_b[3];         /* rad/s (gyro) */
} kestrel_state;

typedef struct kestrel_setpoint {
  int32_t mode; /* kestrel_mode */
  float value[4];
} kestrel_setpoint;

typedef struct kestrel_output {
  int32_t num_motors;
  float motor_command[KESTREL_MAX_MOTORS];  /* allocated thrust normalised to its range, 0..1 */
  float thrust_setpoint_N[KESTREL_MAX_MOTORS]; /* allocated thrust per motor (N) */
  float thrust_N[KESTREL_MAX_MOTORS];       /* motor-model thrust after this step (N); = setpoint without the model */
  float wrench_b[6];                        /* controller output [fx fy fz tx ty tz] */
  uint32_t faults;                          /* latched fault bits (kestrel_faults()) */
  uint16_t saturated_mask;                  /* bit i: motor i at or beyond a limit this step */
} kestrel_output;

/* Size of the C++ control stack in the storage (<= KESTREL_STORAGE_BYTES). */
size_t kestrel_storage_used(void);

/* Fills `params` from a preset. KESTREL_INVALID_ARGUMENT for an unknown preset. */
kestrel_status kestrel_default_params(int32_t preset, kestrel_params* params);

/* Builds the stack in `storage` (computes the allocation pseudo-inverse once: the only costly
 * call). On failure the storage is left unusable (kestrel_step returns INVALID_ARGUMENT). */
kestrel_status kestrel_init(kestrel_storage* storage, int32_t preset);
kestrel_status kestrel_init_params(kestrel_storage* storage, const kestrel_params* params);

/* One control step at a fixed period dt_s (0 < dt_s <= KESTREL_MAX_DT_S): setpoint -> wrench ->
 * motor thrusts (-> motor model). NaN in the state or the setpoint holds the last safe output
 * (NON_FINITE_INPUT). Finite inputs so large that a stage overflows hold the last finite output
 * (NON_FINITE_OUTPUT). For any input, every output is finite and motor_command is in [0, 1];
 * KESTREL_OK means no stage held or replaced anything. KESTREL_INVALID_ARGUMENT (bad mode, dt_s,
 * or non-unit quaternion) leaves the stack and `out` unchanged. */
kestrel_status kestrel_step(kestrel_storage* storage, const kestrel_state* state, const kestrel_setpoint* setpoint,
                            float dt_s, kestrel_output* out);

/* Latched fault bits of every stage (the rank deficiency of a flat multirotor is not a fault). */
uint32_t kestrel_faults(const kestrel_storage* storage);
void kestrel_clear_faults(kestrel_storage* storage);

/* Tells the stack that motor `motor` lost thrust: thrust_scale 0 dead, (0, 1) weak, 1 healthy.
 * Rebuilds the allocation (pseudo-inverse) without it, so the next steps redistribute its share
 * to the other motors, and marks it in the motor model. Not for the fast loop: costs one
 * pseudo-inverse. */
kestrel_status kestrel_inject_motor_failure(kestrel_storage* storage, int32_t motor, float thrust_scale);

/* Normalised motor command (0..1) -> PWM pulse width in microseconds, [min_us, max_us]. */
float kestrel_command_to_pwm_us(float command, float min_us, float max_us);

#ifdef __cplusplus
}
#endif

#endif /* KESTREL_KESTREL_H */
