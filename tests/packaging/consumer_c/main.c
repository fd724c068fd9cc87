/* Hover: each of the four motors carries a quarter of the weight. Exit status 0 only if the C API
 * says so; on bare metal the image is linked, not run (ctest reads its symbols instead). */
#include <kestrel/kestrel.h>

#include "consumer.h"

int main(void) {
  kestrel_params params;
  float thrust_N[4];
  float expected_N;
  int i;
  if (kestrel_default_params(KESTREL_PRESET_BASE_QUADROTOR, &params) != KESTREL_OK) return 1;
  if (consumer_init() != 0) return 2;
  if (consumer_hover(thrust_N) != 4) return 3;
  expected_N = params.mass_kg * 9.81f / 4.0f;
  for (i = 0; i < 4; ++i) {
    if (!(thrust_N[i] > expected_N - 0.01f && thrust_N[i] < expected_N + 0.01f)) return 10 + i;
  }
  return legacy_mixer_ok() ? 0 : 4;
}
