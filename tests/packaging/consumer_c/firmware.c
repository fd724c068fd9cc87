/* What any bare-metal image linked with newlib's crt0 provides, with or without Kestrel (an empty
 * main needs it too): _exit, which crt0 reaches through exit() after main. A real firmware's own
 * startup code replaces crt0; --specs=nosys.specs would provide the stub instead. Kestrel's
 * libraries need no syscall and no hook: the assertion hook is the package's weak default. */
void _exit(int status);
void _exit(int status) {
  for (;;) {
  }
}
