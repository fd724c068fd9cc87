// LD_PRELOAD diagnostic for bench/sim/intel_core.sh (issue 18): prints XINUSE (xgetbv with ecx = 1:
// which parts of the x86 vector state are in use; bit 2 = the AVX upper halves) of the main thread
// when the program starts and when it exits. Build: gcc -O2 -shared -fPIC -o xinuse_preload.so
// bench/sim/xinuse_preload.c (x86-64 with XGETBV ECX=1 only).
#include <stdio.h>
#include <stdint.h>
static uint64_t xinuse(void) { uint32_t lo, hi; __asm__ volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(1)); return ((uint64_t)hi << 32) | lo; }
__attribute__((constructor)) static void at_start(void) { fprintf(stderr, "xinuse_preload: XINUSE at start 0x%03llx\n", (unsigned long long)xinuse()); }
__attribute__((destructor)) static void at_exit_(void) { fprintf(stderr, "xinuse_preload: XINUSE at exit 0x%03llx\n", (unsigned long long)xinuse()); }
