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
 *
 * The guide (storage, params, custom airframes, the validation rules, fault and condition bits,
 * the motor order of each preset, the PWM curve) is docs/capi.md in the repository.
 *
 * Motor order of the presets (body frame x forward, y left, seen from above; CCW = direction +1
 * about the thrust axis +z, the body then feels a clockwise reaction torque; index = position in
 * motor_command[], thrust_N[], ...):
 *
 *   KESTREL_PRESET_BASE_QUADROTOR (arm 0.184 m,   KESTREL_PRESET_X500 (PX4 quad-X order,
 *   rotors at (+-0.13, +-0.13, 0) m)              rotors at (+-0.175, +-0.175, 0) m)
 *
 *             front (+x)                                   front (+x)
 *        3 CW         0 CCW                           2 CW          0 CCW
 *   (+0.13,+0.13)  (+0.13,-0.13)                 (+0.175,+0.175) (+0.175,-0.175)
 *              \     /                                     \     /
 *               [body]   -> right (-y)                      [body]
 *              /     \                                     /     \
 *   (-0.13,+0.13)  (-0.13,-0.13)                 (-0.175,+0.175) (-0.175,-0.175)
 *        2 CCW        1 CW                            1 CCW         3 CW
 *
 *   KESTREL_PRESET_HEXAROTOR (flat hex-X, arm 0.25 m, counter-clockwise from the front-right arm):
 *     0 (+0.2165, -0.125) front-right  CCW     3 (-0.2165, +0.125) rear-left   CW
 *     1 (+0.2165, +0.125) front-left   CW      4 (-0.2165, -0.125) rear-right  CCW
 *     2 ( 0,      +0.25 ) left         CCW     5 ( 0,      -0.25 ) right       CW
 *
 * kestrel_airframe_from_preset() returns these numbers as data.
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
  KESTREL_NON_FINITE_OUTPUT = 6, /* finite inputs overflowed inside a stage (absurd magnitudes): the last
                                   finite output was held, KESTREL_FAULT_NON_FINITE_OUTPUT latched */
  /* Values 7 and up exist in the C API only (not kestrel::Status values). */
  KESTREL_CLIPPED = 7,            /* kestrel_step: a setpoint value was outside [KESTREL_SETPOINT_MIN,
                                     KESTREL_SETPOINT_MAX] and was clipped; the output is the controller's
                                     for the clipped setpoint (KESTREL_FAULT_COMMAND_OUT_OF_RANGE) */
  KESTREL_INSUFFICIENT_THRUST = 8 /* init: the rotors' largest total thrust along body +z is below
                                     mass * 9.81 (thrust-to-weight < 1); nothing was built */
} kestrel_status;

/* Every setpoint value is clipped to this range (the controller's action range, as Aerial Gym's):
 * metres in KESTREL_MODE_POSITION (a world box of +-10 m), m/s, rad/s, ... A clipped step returns
 * KESTREL_CLIPPED. A position more than a few metres away gives a large (up to full-tilt)
 * correction: step the setpoint along a trajectory instead. */
#define KESTREL_SETPOINT_MIN (-10.0f)
#define KESTREL_SETPOINT_MAX 10.0f

/* Largest control period kestrel_step() accepts (s). Larger steps make no sense for a control loop
 * and overflow the motor model (around 1e16 s); they are refused with KESTREL_INVALID_ARGUMENT. */
#define KESTREL_MAX_DT_S 1.0f

/* kestrel_state.orientation_xyzw must be a unit quaternion within this tolerance:
 * | |q| - 1 | <= KESTREL_QUAT_NORM_TOLERANCE, else kestrel_step() returns KESTREL_INVALID_ARGUMENT
 * (a zero or unnormalised quaternion gives a meaningless rotation). An estimator that renormalises
 * each update is far inside it. A NaN/inf component is a non-finite input instead (held output,
 * KESTREL_NON_FINITE_INPUT). */
#define KESTREL_QUAT_NORM_TOLERANCE 1e-3f

/* Fault and condition bits (values of the C++ kestrel::Fault). kestrel_output.conditions holds every
 * bit the last kestrel_step raised (per step: 0 again when the cause is gone). kestrel_output.faults
 * and kestrel_faults() hold the latched faults: the bits of KESTREL_LATCHED_FAULTS ever raised,
 * until kestrel_clear_faults(). A normal flight (take-off included) has faults == 0.
 *                                          latched  meaning
 *   KESTREL_FAULT_NON_FINITE_COMMAND        yes     NaN/inf in the setpoint: last safe output held
 *   KESTREL_FAULT_NON_FINITE_STATE          yes     NaN/inf in the state: last safe output held
 *   KESTREL_FAULT_COMMAND_OUT_OF_RANGE      yes     a setpoint value was clipped (KESTREL_CLIPPED)
 *   KESTREL_FAULT_SATURATED                 no      a motor at or beyond its limit (see saturated_mask);
 *                                                   normal at take-off and in hard manoeuvres
 *   KESTREL_FAULT_SINGULAR                  no      the desired attitude was undefined (zero force
 *                                                   command): fallback attitude (KESTREL_SINGULAR)
 *   KESTREL_FAULT_UNALLOCATED               no      part of the wrench could not be produced
 *   KESTREL_FAULT_MOTOR_FAILURE             yes     a motor is marked dead or weak (a condition on
 *                                                   every step while it is)
 *   KESTREL_FAULT_NOT_CONVERGED             no      an iterative allocator hit its bound
 *   KESTREL_FAULT_NON_FINITE_OUTPUT         yes     a stage overflowed: last finite output held */
#define KESTREL_FAULT_NON_FINITE_COMMAND 0x001u
#define KESTREL_FAULT_NON_FINITE_STATE 0x002u
#define KESTREL_FAULT_COMMAND_OUT_OF_RANGE 0x004u
#define KESTREL_FAULT_SATURATED 0x008u
#define KESTREL_FAULT_SINGULAR 0x010u
#define KESTREL_FAULT_UNALLOCATED 0x020u
#define KESTREL_FAULT_MOTOR_FAILURE 0x040u
#define KESTREL_FAULT_NOT_CONVERGED 0x080u
#define KESTREL_FAULT_NON_FINITE_OUTPUT 0x100u
#define KESTREL_LATCHED_FAULTS                                                                              \
  (KESTREL_FAULT_NON_FINITE_COMMAND | KESTREL_FAULT_NON_FINITE_STATE | KESTREL_FAULT_COMMAND_OUT_OF_RANGE | \
   KESTREL_FAULT_MOTOR_FAILURE | KESTREL_FAULT_NON_FINITE_OUTPUT)

/* Airframe presets (ids of kestrel::allocation::AirframePreset that the C API supports); motor
 * order and spin directions in the picture at the top of this file. */
typedef enum kestrel_preset {
  KESTREL_PRESET_BASE_QUADROTOR = 0, /* Aerial Gym's 0.25 kg quad, [0, 2] N per motor, ratio 0.01 */
  KESTREL_PRESET_HEXAROTOR = 4,      /* 2.4 kg flat hex-X, [0, 8] N per motor, ratio 0.016 */
  KESTREL_PRESET_X500 = 5            /* Holybro X500 class quad, 2.0 kg, [0, 10] N per motor, ratio 0.016 */
} kestrel_preset;

/* What the setpoint's four values mean (Aerial Gym's controller registry, kestrel::ControllerKind). */
typedef enum kestrel_mode {
  KESTREL_MODE_POSITION = 0, /* [x_w, y_w, z_w, yaw] m, m, m, rad */
  KESTREL_MODE_VELOCITY = 1, /* [vx_v, vy_v, vz_v, yaw_rate] m/s in the yaw frame, rad/s */
  KESTREL_MODE_ATTITUDE = 3, /* [thrust, roll, pitch, yaw_rate]: fz = (thrust + 1) m g */
  KESTREL_MODE_RATES = 4     /* [thrust, p, q, r] body rates rad/s */
} kestrel_mode;

/* Everything kestrel_init_params() reads: plain data with documented defaults
 * (kestrel_default_params() fills them from a preset). Refused at init (KESTREL_INVALID_ARGUMENT)
 * outside the ranges given here; a mass the rotors cannot lift gives KESTREL_INSUFFICIENT_THRUST. */
typedef struct kestrel_params {
  int32_t preset;             /* kestrel_preset: airframe geometry, motor limits and motor model
                                 (ignored by kestrel_init_airframe, which takes them from its airframe) */
  float mass_kg;              /* (0, 1e6], and mass * 9.81 <= the largest total thrust along body +z */
  float inertia_diag_kgm2[3]; /* body-axis principal moments, each in (0, 1e6] */
  float k_pos[3];             /* (m/s^2) per m; every gain 0 <= k <= 1e6 (kestrel::kLeeMaxGain) */
  float k_vel[3];             /* (m/s^2) per m/s */
  float k_rot[3];             /* N m per unit attitude error */
  float k_angvel[3];          /* N m per rad/s */
  float max_yaw_rate_radps;   /* [0, 1e6] */
  float yaw_headroom;         /* desaturation: fraction of the range yaw may exceed max by (PX4: 0.15), [0, 1e6] */
  int32_t use_motor_model;    /* non-zero: step the motor model (predicted thrust in out->thrust_N) */
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

/* One rotor of a custom airframe. */
typedef struct kestrel_rotor {
  float position_b_m[3]; /* hub relative to the centre of mass, body frame (x fwd, y left, z up), |.| <= 100 */
  float axis_b[3];       /* thrust direction, body frame: finite, non-zero; normalised at init */
  int32_t direction;     /* +1: spins counter-clockwise seen from the tip of axis_b (from above for
                            +z), the body feels a clockwise reaction torque; -1: clockwise */
  float thrust_min_N;    /* this motor's thrust range: finite, min < max, |.| <= 1e6; min >= 0 */
  float thrust_max_N;    /*   with the rotor-speed motor model (thrust_constant > 0) */
} kestrel_rotor;

/* A custom airframe for kestrel_init_airframe(): what a real vehicle's geometry and motors are.
 * The allocation is built from it (the column of rotor i: force axis_i, torque
 * position_i x axis_i - direction_i * torque_to_thrust_m * axis_i); motor i is motor_command[i]. */
typedef struct kestrel_airframe {
  int32_t num_rotors;                     /* 1..KESTREL_MAX_MOTORS */
  kestrel_rotor rotor[KESTREL_MAX_MOTORS]; /* rotor[num_rotors..] ignored */
  float torque_to_thrust_m; /* km / kf: reaction torque per newton of thrust (N m / N), [0, 1], every rotor */
  /* Motor model (read when kestrel_params.use_motor_model is non-zero): a first-order lag of the
   * thrust toward its setpoint with separate time constants for rising and falling thrust,
   * integrated (RK4) on the rotor speed w (thrust = kf w^2) when thrust_constant > 0, else on the
   * thrust itself. */
  float thrust_constant;      /* kf, N / (rad/s)^2: [0, 1]; 0 = thrust-state model */
  float time_constant_up_s;   /* (0, 10] */
  float time_constant_down_s; /* (0, 10] */
} kestrel_airframe;

typedef struct kestrel_output {
  int32_t num_motors;
  float motor_command[KESTREL_MAX_MOTORS];  /* allocated thrust as a fraction of motor i's range:
                                               (thrust - min_i) / (max_i - min_i), 0..1 (to PWM:
                                               kestrel_thrust_to_pwm_us) */
  float thrust_setpoint_N[KESTREL_MAX_MOTORS]; /* allocated thrust per motor (N) */
  float thrust_N[KESTREL_MAX_MOTORS];       /* motor-model thrust after this step (N); = setpoint without the model */
  float wrench_b[6];                        /* controller output [fx fy fz tx ty tz] */
  uint32_t faults;                          /* latched faults (KESTREL_LATCHED_FAULTS bits; kestrel_faults()) */
  uint16_t saturated_mask;                  /* bit i: motor i at or beyond a limit this step */
  uint16_t conditions;                      /* every fault bit this step raised (see the table above);
                                               fills what was padding: the struct's size is unchanged */
} kestrel_output;

/* Size of the C++ control stack in the storage (<= KESTREL_STORAGE_BYTES). */
size_t kestrel_storage_used(void);

/* Fills `params` from a preset. KESTREL_INVALID_ARGUMENT for an unknown preset. */
kestrel_status kestrel_default_params(int32_t preset, kestrel_params* params);

/* Fills `airframe` with a preset's geometry, directions, limits and motor constants (the numbers
 * of the picture at the top). KESTREL_INVALID_ARGUMENT for an unknown preset. kestrel_init_airframe
 * with it gives the preset's outputs bit for bit for the hexarotor and the X500 and without the
 * motor model; the base quadrotor's motor model in kestrel_init is Aerial Gym's (discrete-step
 * approximation, kf drawn in [9.26e-6, 1.83e-5]), here the continuous one at the midpoint kf. */
kestrel_status kestrel_airframe_from_preset(int32_t preset, kestrel_airframe* airframe);

/* Builds the stack in `storage` (computes the allocation pseudo-inverse once: the only costly
 * call). Validates everything first (docs/capi.md, "Validation"): KESTREL_INVALID_ARGUMENT for a
 * value outside its range (a negative gain, a zero inertia, a bad rotor), KESTREL_SINGULAR for an
 * airframe that cannot produce the collective thrust and all three torques independently,
 * KESTREL_INSUFFICIENT_THRUST when the rotors cannot lift mass * 9.81 N along body +z. On any
 * failure the storage is left unusable (kestrel_step returns KESTREL_INVALID_ARGUMENT), even if it
 * held a working stack before. */
kestrel_status kestrel_init(kestrel_storage* storage, int32_t preset);
kestrel_status kestrel_init_params(kestrel_storage* storage, const kestrel_params* params);
/* A custom airframe (`airframe`) with the controller of `params` (mass, inertia, gains, yaw limit,
 * headroom, motor model on/off; params->preset is ignored). Added beside kestrel_init_params so
 * that kestrel_params keeps its layout (firmware built against the older header still links). */
kestrel_status kestrel_init_airframe(kestrel_storage* storage, const kestrel_airframe* airframe,
                                     const kestrel_params* params);

/* One control step at a fixed period dt_s (0 < dt_s <= KESTREL_MAX_DT_S): setpoint -> wrench ->
 * motor thrusts (-> motor model). For any input, every output is finite and motor_command is in
 * [0, 1]. The status, most severe first:
 *   KESTREL_INVALID_ARGUMENT   bad mode, dt_s outside (0, KESTREL_MAX_DT_S] (1e9 s too), or a finite
 *                              quaternion off unit length: the stack and `out` are unchanged;
 *   KESTREL_NON_FINITE_INPUT   NaN/inf in the state or the setpoint: the last safe output held;
 *   KESTREL_NON_FINITE_OUTPUT  finite inputs so large that a stage overflowed: last finite output held;
 *   KESTREL_CLIPPED            a setpoint value outside [KESTREL_SETPOINT_MIN, KESTREL_SETPOINT_MAX]
 *                              was clipped; the output is the controller's for the clipped value;
 *   KESTREL_SINGULAR           the controller's desired attitude was undefined: fallback attitude;
 *   KESTREL_OK                 nothing was refused, held, clipped or replaced (motor saturation is
 *                              normal operation: see out->conditions and out->saturated_mask). */
kestrel_status kestrel_step(kestrel_storage* storage, const kestrel_state* state, const kestrel_setpoint* setpoint,
                            float dt_s, kestrel_output* out);

/* Latched faults (KESTREL_LATCHED_FAULTS bits; the rank deficiency of a flat multirotor is not a
 * fault, nor is saturation: those are per-step conditions in kestrel_output.conditions). */
uint32_t kestrel_faults(const kestrel_storage* storage);
/* Clears the latched faults. A dead or weak motor raises KESTREL_FAULT_MOTOR_FAILURE again on the
 * next step (a motor failure is not undone by clearing the flag). */
void kestrel_clear_faults(kestrel_storage* storage);

/* Tells the stack that motor `motor` lost thrust: thrust_scale 0 dead, (0, 1) weak, 1 healthy.
 * Rebuilds the allocation (pseudo-inverse) without it, so the next steps redistribute its share
 * to the other motors, and marks it in the motor model. Not for the fast loop: costs one
 * pseudo-inverse. */
kestrel_status kestrel_inject_motor_failure(kestrel_storage* storage, int32_t motor, float thrust_scale);

/* Motor command (the fraction of the motor's thrust range, kestrel_output.motor_command) -> ESC
 * throttle in [0, 1], through PX4's thrust model THR_MDL_FAC = k in [0, 1]:
 *   thrust fraction = (1 - k) u + k u^2   (u: throttle),
 * inverted: u = 2 t / ((1 - k) + sqrt((1 - k)^2 + 4 k t)). k = 0: linear (an ESC that linearises
 * thrust itself); k = 1: thrust proportional to throttle squared, u = sqrt(t) (a fixed-pitch
 * propeller on a plain ESC, thrust ~ rpm^2 ~ throttle^2); PX4's default 0 and typical fits
 * 0.3..0.7 lie between. The command is clamped to [0, 1] (NaN -> 0: motors idle), k likewise
 * (NaN -> 0). */
float kestrel_command_to_throttle(float command, float thr_mdl_fac);
/* min_us + kestrel_command_to_throttle(command, thr_mdl_fac) * (max_us - min_us): the PWM pulse
 * width in microseconds for a motor command. Use this one for a real ESC. */
float kestrel_thrust_to_pwm_us(float command, float thr_mdl_fac, float min_us, float max_us);
/* Deprecated (kept with its behaviour): the linear map min_us + command * (max_us - min_us), i.e.
 * kestrel_thrust_to_pwm_us(command, 0, ...). Right only when the ESC or firmware linearises thrust;
 * on a plain ESC it gives too little thrust below full throttle (with k = 1 half the thrust needs
 * ~71 % throttle; the linear map sends 50 %, a quarter of the thrust). */
float kestrel_command_to_pwm_us(float command, float min_us, float max_us);

#ifdef __cplusplus
}
#endif

#endif /* KESTREL_KESTREL_H */
