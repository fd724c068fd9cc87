/* Hover: each of the four motors carries a quarter of the weight. */
int consumer_init(void);
float consumer_hover_command(void);
float consumer_quad_mass(void);
int consumer_quad_rotors(void);

int main(void) {
  float c, expected;
  if (consumer_init() != 0) return 1;
  c = consumer_hover_command();
  expected = consumer_quad_mass() * 9.81f / (float)consumer_quad_rotors() / 2.0f; /* range [0, 2] N */
  return (c > expected - 0.01f && c < expected + 0.01f) ? 0 : 2;
}
