/* C firmware module: one control stack in static storage, stepped from the main loop. */
#include <kestrel/kestrel.h>

static kestrel_storage g_stack;

int consumer_init(void) { return kestrel_init(&g_stack, KESTREL_PRESET_BASE_QUADROTOR) == KESTREL_OK ? 0 : 1; }

float consumer_hover_command(void) {
  kestrel_state s = {{0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}};
  const kestrel_setpoint sp = {KESTREL_MODE_POSITION, {0.0f, 0.0f, 1.0f, 0.0f}};
  kestrel_output out;
  if (kestrel_step(&g_stack, &s, &sp, 0.002f, &out) != KESTREL_OK) return -1.0f;
  return out.motor_command[0];
}
