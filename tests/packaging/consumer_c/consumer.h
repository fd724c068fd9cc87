#ifndef CONSUMER_H
#define CONSUMER_H
int consumer_init(void);
/* Steps the stack once at hover; writes the four thrust setpoints (N), returns the motor count. */
int consumer_hover(float thrust_N[4]);
int legacy_mixer_ok(void);
#endif
