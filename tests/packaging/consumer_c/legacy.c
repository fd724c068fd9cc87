/* "Legacy" firmware code that this project's flags accept and Kestrel's would not: a local that
 * shadows another (-Wshadow), a GNU case range (-Wpedantic), an unused callback parameter. If the
 * package pushed Kestrel's warning policy onto the consumer, this file would break its build. */
#include "consumer.h"

static int motors_for(int code, void* user) {
  switch (code) {
    case 1 ... 3:
      return 4;
    default:
      return 6;
  }
}

int legacy_mixer_ok(void) {
  int count = motors_for(2, 0);
  {
    int count = motors_for(9, 0);
    if (count != 6) return 0;
  }
  return count == 4;
}
