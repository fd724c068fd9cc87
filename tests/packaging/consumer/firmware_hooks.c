/* What a bare-metal firmware provides to the Kestrel core: the assertion hook (kernel/assert.hpp
 * calls it when no handler is installed). A real firmware would log and enter its failsafe. */
void kestrel_platform_assert_default(const char* expr, const char* file, int line);
void kestrel_platform_assert_default(const char* expr, const char* file, int line) {
  (void)expr;
  (void)file;
  (void)line;
  for (;;) {
  }
}
