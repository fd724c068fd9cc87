// Hover through the C API, checked against the C++ core's own preset: each of the motors carries
// its share of the weight. Exit status 0 only if both agree; on bare metal the image is linked,
// not run (ctest reads its symbols instead).
#include <kestrel/kestrel.h>

float consumer_quad_mass();
int consumer_quad_rotors();
bool legacy_ok();

namespace {
kestrel_storage g_stack;
}

int main() {
  if (kestrel_init(&g_stack, KESTREL_PRESET_BASE_QUADROTOR) != KESTREL_OK) return 1;
  kestrel_state s = {{0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}};
  const kestrel_setpoint sp = {KESTREL_MODE_POSITION, {0.0f, 0.0f, 1.0f, 0.0f}};
  kestrel_output out{};
  if (kestrel_step(&g_stack, &s, &sp, 0.002f, &out) != KESTREL_OK) return 2;
  const int rotors = consumer_quad_rotors();
  if (rotors != 4 || out.num_motors != rotors) return 3;
  const float expected_N = consumer_quad_mass() * 9.81f / static_cast<float>(rotors);
  for (int i = 0; i < rotors; ++i) {
    if (!(out.thrust_setpoint_N[i] > expected_N - 0.01f && out.thrust_setpoint_N[i] < expected_N + 0.01f)) return 10 + i;
  }
  return legacy_ok() ? 0 : 4;
}
