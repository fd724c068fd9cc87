// Golden parity with the Aerial Gym motor model (golden/motor_model.json): every configuration x
// time step x step x motor the file lists, within its recommended tolerance (abs 1e-5 + rel 1e-5
// in the public set). Counts come from the file; it must cover both integrators and both states
// (thrust and rotor speed), so an empty or truncated file fails.
//
// Streamed: each configuration's reference_thrust_N (steps x 4, at most kMaxSteps) comes before
// its runs, so the reference is kept in a static array and every run is simulated and compared as
// it is read.
#include <cstring>

#include "alloc_test_util.hpp"
#include "golden_tol.hpp"
#include "json_pull.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "ktest.hpp"
#include "test_io.hpp"

using namespace alloc_test;

namespace {

constexpr int kMaxSteps = 200;  // the public set's traces; static storage on the MCU
constexpr int kMotors = 4;

float g_reference[kMaxSteps * kMotors];
float g_expected[kMaxSteps * kMotors];

bool read_params(ktest::JsonReader& r, MotorModelConfig& cfg) {
  cfg = MotorModelConfig();
  if (!r.begin_object()) return false;
  char key[64];
  int fields = 0;
  while (r.next_key(key, sizeof(key))) {
    float v = 0;
    bool b = false;
    if (std::strcmp(key, "integration_scheme") == 0) {
      char scheme[16];
      r.read_string(scheme, sizeof(scheme));
      cfg.integrator = std::strcmp(scheme, "euler") == 0 ? MotorIntegrator::euler : MotorIntegrator::rk4;
      ++fields;
    } else if (std::strcmp(key, "use_rps") == 0) {
      fields += r.read_bool(b);
      cfg.use_rps = b;
    } else if (std::strcmp(key, "use_discrete_approximation") == 0) {
      fields += r.read_bool(b);
      cfg.use_discrete_approximation = b;
    } else if (std::strcmp(key, "time_constant_increasing_s") == 0) {
      fields += r.read_float(v);
      cfg.time_constant_increasing_min_s = cfg.time_constant_increasing_max_s = v;
    } else if (std::strcmp(key, "time_constant_decreasing_s") == 0) {
      fields += r.read_float(v);
      cfg.time_constant_decreasing_min_s = cfg.time_constant_decreasing_max_s = v;
    } else if (std::strcmp(key, "min_thrust_N") == 0) {
      fields += r.read_float(v);
      cfg.thrust_min_N = v;
    } else if (std::strcmp(key, "max_thrust_N") == 0) {
      fields += r.read_float(v);
      cfg.thrust_max_N = v;
    } else if (std::strcmp(key, "max_rate") == 0) {
      fields += r.read_float(v);
      cfg.max_rate = v;
    } else if (std::strcmp(key, "thrust_constant") == 0) {
      if (r.peek_null()) {
        r.skip_value();
      } else {
        r.read_float(v);
        cfg.thrust_constant_min = cfg.thrust_constant_max = v;
      }
      ++fields;
    } else if (std::strcmp(key, "num_motors") == 0) {
      fields += r.read_int(cfg.num_motors);
    } else {
      r.skip_value();
    }
  }
  return r.ok() && fields == 10;
}

struct Totals {
  int configurations = 0;
  int runs = 0;
  int rps_runs = 0;
  int rk4_runs = 0;
  int steps = 0;  // steps compared, over all runs
};

/// Simulates one run from the stored reference and compares every step.
void run_and_compare(const MotorModelConfig& cfg, const float* initial, real dt_s, int steps, const ktest::GoldenTol& tol,
                     CloseCounter& cc, int run_id) {
  MotorModelState state;
  RngStream rng(1, 0, kPurposeMotors);  // min == max: the draws return the fixed constants
  real init[kMotors];
  for (int m = 0; m < kMotors; ++m) init[m] = initial[m];
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = motor_model_reset(cfg, state, rng, init));
  KASSERT_EQ(static_cast<int>(st), static_cast<int>(Status::ok));
  for (int k = 0; k < steps; ++k) {
    real ref[kMotors];
    for (int m = 0; m < kMotors; ++m) ref[m] = g_reference[k * kMotors + m];
    KEXPECT_NO_HEAP(st = motor_model_step(cfg, state, ref, dt_s));
    if (st != Status::ok) {
      KEXPECT_EQ(static_cast<int>(st), static_cast<int>(Status::ok));
    }
    for (int m = 0; m < kMotors; ++m) {
      cc.check(state.thrust_N[m], g_expected[k * kMotors + m], tol.abs, tol.rel, "motor thrust_N", run_id * 1000 + k);
    }
  }
  KEXPECT_FALSE(state.faults.any());
}

}  // namespace

KTEST(MotorGolden, AllConfigurationsBothTimeSteps) {
  ktest::JsonReader r;
  KASSERT_TRUE(r.open(ktest::golden_path("motor_model.json")));
  KASSERT_TRUE(r.begin_object());
  ktest::GoldenTol tol = {1e-5, 1e-5};  // unless conventions.recommended_tolerance says otherwise
  KASSERT_TRUE(r.find_key("conventions"));  // listed first
  KASSERT_TRUE(ktest::read_conventions_tolerance(r, [&](ktest::JsonReader& t) { return ktest::read_tolerance(t, tol); }));
  KASSERT_TRUE(r.find_key("configurations"));
  KASSERT_TRUE(r.begin_array());

  Totals totals;
  int steps = 0;
  CloseCounter cc;
  MotorModelConfig cfg;
  float initial[kMotors] = {0, 0, 0, 0};
  while (r.next_element()) {
    KASSERT_TRUE(r.begin_object());
    bool have_params = false, have_reference = false, have_initial = false;
    char key[48];
    while (r.next_key(key, sizeof(key))) {
      if (std::strcmp(key, "params") == 0) {
        have_params = read_params(r, cfg);
        KASSERT_TRUE(have_params);
        KEXPECT_EQ(cfg.num_motors, kMotors);
        KEXPECT_EQ(static_cast<int>(validate(cfg)), static_cast<int>(Status::ok));
      } else if (std::strcmp(key, "reference_thrust_N") == 0) {
        const int n = r.read_numbers(g_reference, kMaxSteps * kMotors);
        KASSERT_TRUE(n > 0 && n <= kMaxSteps * kMotors && n % kMotors == 0);
        steps = n / kMotors;
        have_reference = true;
      } else if (std::strcmp(key, "initial_thrust_N") == 0) {
        KASSERT_EQ(r.read_numbers(initial, kMotors), kMotors);
        have_initial = true;
      } else if (std::strcmp(key, "runs") == 0) {
        // The file lists params, reference and initial state before the runs.
        KASSERT_TRUE(have_params && have_reference && have_initial);
        KASSERT_TRUE(r.begin_array());
        const int runs_before = totals.runs;
        while (r.next_element()) {
          KASSERT_TRUE(r.begin_object());
          float dt = 0;
          bool have_dt = false, have_thrust = false;
          char run_key[48];
          while (r.next_key(run_key, sizeof(run_key))) {
            if (std::strcmp(run_key, "dt_s") == 0) {
              have_dt = r.read_float(dt);
            } else if (std::strcmp(run_key, "thrust_N") == 0) {
              KASSERT_EQ(r.read_numbers(g_expected, kMaxSteps * kMotors), steps * kMotors);
              have_thrust = true;
            } else {
              r.skip_value();
            }
          }
          KASSERT_TRUE(have_dt && have_thrust);
          run_and_compare(cfg, initial, dt, steps, tol, cc, totals.runs);
          ++totals.runs;
          totals.rps_runs += cfg.use_rps;
          totals.rk4_runs += cfg.integrator == MotorIntegrator::rk4;
          totals.steps += steps;
        }
        KEXPECT_GE(totals.runs - runs_before, 1);  // every configuration has a run
      } else {
        r.skip_value();
      }
    }
    ++totals.configurations;
  }
  KEXPECT_TRUE(r.ok());
  // Whatever the file's mix: at least one configuration, and runs of each integrator (Euler, RK4)
  // and each state (thrust, rotor speed), every step of every run compared.
  KEXPECT_GE(totals.configurations, 1);
  KEXPECT_GE(totals.rps_runs, 1);
  KEXPECT_GE(totals.runs - totals.rps_runs, 1);
  KEXPECT_GE(totals.rk4_runs, 1);
  KEXPECT_GE(totals.runs - totals.rk4_runs, 1);
  KEXPECT_EQ(cc.checked, totals.steps * kMotors);
  KEXPECT_EQ(cc.failed, 0);
  KEXPECT_EQ(cc.first_bad_id, -1);  // run * 1000 + step of the first failure
}
