// Golden parity with the Aerial Gym motor model (golden/motor_model.json): 9 configurations x
// 2 time steps x 200 steps x 4 motors, abs 1e-5 + rel 1e-5 per step.
//
// Streamed: each configuration's reference_thrust_N (200 x 4) comes before its runs, so the
// reference is kept in a static array and every run is simulated and compared as it is read.
#include <cstring>

#include "alloc_test_util.hpp"
#include "json_pull.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "ktest.hpp"
#include "test_io.hpp"

using namespace alloc_test;

namespace {

constexpr int kSteps = 200;
constexpr int kMotors = 4;

float g_reference[kSteps * kMotors];
float g_expected[kSteps * kMotors];

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
};

/// Simulates one run from the stored reference and compares every step.
void run_and_compare(const MotorModelConfig& cfg, const float* initial, real dt_s, CloseCounter& cc, int run_id) {
  MotorModelState state;
  RngStream rng(1, 0, kPurposeMotors);  // min == max: the draws return the fixed constants
  real init[kMotors];
  for (int m = 0; m < kMotors; ++m) init[m] = initial[m];
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = motor_model_reset(cfg, state, rng, init));
  KASSERT_EQ(static_cast<int>(st), static_cast<int>(Status::ok));
  for (int k = 0; k < kSteps; ++k) {
    real ref[kMotors];
    for (int m = 0; m < kMotors; ++m) ref[m] = g_reference[k * kMotors + m];
    KEXPECT_NO_HEAP(st = motor_model_step(cfg, state, ref, dt_s));
    if (st != Status::ok) {
      KEXPECT_EQ(static_cast<int>(st), static_cast<int>(Status::ok));
    }
    for (int m = 0; m < kMotors; ++m) {
      cc.check(state.thrust_N[m], g_expected[k * kMotors + m], 1e-5, 1e-5, "motor thrust_N", run_id * 1000 + k);
    }
  }
  KEXPECT_FALSE(state.faults.any());
}

}  // namespace

KTEST(MotorGolden, AllConfigurationsBothTimeSteps) {
  ktest::JsonReader r;
  KASSERT_TRUE(r.open(ktest::golden_path("motor_model.json")));
  KASSERT_TRUE(r.begin_object());
  KASSERT_TRUE(r.find_key("configurations"));
  KASSERT_TRUE(r.begin_array());

  Totals totals;
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
        KASSERT_EQ(r.read_numbers(g_reference, kSteps * kMotors), kSteps * kMotors);
        have_reference = true;
      } else if (std::strcmp(key, "initial_thrust_N") == 0) {
        KASSERT_EQ(r.read_numbers(initial, kMotors), kMotors);
        have_initial = true;
      } else if (std::strcmp(key, "runs") == 0) {
        // The file lists params, reference and initial state before the runs.
        KASSERT_TRUE(have_params && have_reference && have_initial);
        KASSERT_TRUE(r.begin_array());
        while (r.next_element()) {
          KASSERT_TRUE(r.begin_object());
          float dt = 0;
          bool have_dt = false, have_thrust = false;
          char run_key[48];
          while (r.next_key(run_key, sizeof(run_key))) {
            if (std::strcmp(run_key, "dt_s") == 0) {
              have_dt = r.read_float(dt);
            } else if (std::strcmp(run_key, "thrust_N") == 0) {
              KASSERT_EQ(r.read_numbers(g_expected, kSteps * kMotors), kSteps * kMotors);
              have_thrust = true;
            } else {
              r.skip_value();
            }
          }
          KASSERT_TRUE(have_dt && have_thrust);
          run_and_compare(cfg, initial, dt, cc, totals.runs);
          ++totals.runs;
          totals.rps_runs += cfg.use_rps;
          totals.rk4_runs += cfg.integrator == MotorIntegrator::rk4;
        }
      } else {
        r.skip_value();
      }
    }
    ++totals.configurations;
  }
  KEXPECT_TRUE(r.ok());
  KEXPECT_EQ(totals.configurations, 9);
  KEXPECT_EQ(totals.runs, 18);
  KEXPECT_EQ(totals.rps_runs, 8);   // 4 rotor-speed configurations
  KEXPECT_EQ(totals.rk4_runs, 10);  // 5 RK4 configurations
  KEXPECT_EQ(cc.checked, 18 * kSteps * kMotors);
  KEXPECT_EQ(cc.failed, 0);
  KEXPECT_EQ(cc.first_bad_id, -1);  // run * 1000 + step of the first failure
}
