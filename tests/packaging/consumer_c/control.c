/* C firmware module: one control stack in static storage, stepped from the main loop. */
#include <kestrel/kestrel.h>

#include "consumer.h"

static kestrel_storage g_stack;

int consumer_init(void) { return kestrel_init(&g_stack, KESTREL_PRESET_BASE_QUADROTOR) == KESTREL_OK ? 0 : 1; }

int consumer_hover(float thrust_N[4]) {
  kestrel_state s = {{0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}};
  const kestrel_setpoint sp = {KESTREL_MODE_POSITION, {0.0f, 0.0f, 1.0f, 0.0f}};
  kestrel_output out;
  int i;
  if (kestrel_step(&g_stack, &s, &sp, 0.002f, &out) != KESTREL_OK || out.num_motors != 4) return -1;
  for (i = 0; i < 4; ++i) thrust_N[i] = out.thrust_setpoint_N[i];
  return out.num_motors;
}
