// kestrel_cpu_probe: what the CPU and the process's register state look like where `kestrel run`
// runs (issue 18: why one Intel Xeon core stepped the harness ~3x slower than one AMD EPYC core).
//
// Prints, with no effect on anything else:
//  - the CPU's brand string and the features the batch kernel's dispatch reads (AVX2, AVX-512F);
//  - XINUSE (xgetbv with ecx = 1): which parts of the extended register state the CPU considers in
//    use. Bit 2 (AVX: the upper halves of ymm0-15) set while legacy-SSE code runs can cost: a
//    non-VEX SSE instruction then has to keep the upper half of its destination, which can make it
//    wait for that register's previous value. Measured with this probe (2026-11-27): 11x on the
//    probe's SSE loop on an AMD Zen 5 core, 1.07x on an Intel family 6 model 207 core; the state
//    was clean in every process, thread and run looked at. `vzeroupper` makes it clean;
//  - a clock estimate (a chain of dependent integer multiplies, three cycles each on both vendors);
//    `--ghz COUNT MS` prints COUNT such samples of MS milliseconds (how steady the clock is);
//    `--tput COUNT MS` the same for two throughput-bound loops (independent multiplies, the SSE
//    loop below), which a busy sibling hyperthread slows and a clock sample barely notices;
//  - the time of one legacy-SSE loop (independent multiply-add chains whose registers are reused
//    every iteration, the pattern of compiled float code) in the state the process starts in,
//    after `vzeroupper`, after dirtying the upper halves on purpose, and after a syscall.
// Timings are figures, never assertions.
#include <cpuid.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <thread>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

bool have_xgetbv1() {
  unsigned a, b, c, d;
  if (!__get_cpuid_count(0xD, 1, &a, &b, &c, &d)) return false;
  unsigned a1 = 0, b1 = 0, c1 = 0, d1 = 0;
  __get_cpuid(1, &a1, &b1, &c1, &d1);
  return ((c1 >> 27) & 1u) != 0 && ((a >> 2) & 1u) != 0;  // OSXSAVE and XGETBV with ECX=1
}

// XINUSE: the state components not in their initial configuration.
std::uint64_t xinuse() {
  std::uint32_t lo, hi;
  __asm__ volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(1));
  return (static_cast<std::uint64_t>(hi) << 32) | lo;
}

bool g_xinuse = false;
bool g_avx = false;

void print_xinuse(const char* when) {
  if (!g_xinuse) {
    std::printf("  XINUSE %-40s n/a (no xgetbv ecx=1)\n", when);
    return;
  }
  const std::uint64_t x = xinuse();
  std::printf("  XINUSE %-40s 0x%03llx  (AVX upper halves %s%s)\n", when, static_cast<unsigned long long>(x),
              (x & 4u) ? "IN USE" : "clean", (x & 0xe0u) ? ", AVX-512 state in use" : "");
}

__attribute__((target("avx"))) void vzeroupper() { __asm__ volatile("vzeroupper" ::: "memory"); }
// Writes a non-zero value into the upper halves of ymm0 and ymm15 and leaves it there: no AVX
// target on this function, so the compiler adds no vzeroupper at its end (the assembler takes the
// VEX instructions anyway; only called where the CPU has AVX).
__attribute__((noinline)) void dirty_upper() {
  __asm__ volatile("vpcmpeqd %%ymm0, %%ymm0, %%ymm0\n\tvpcmpeqd %%ymm15, %%ymm15, %%ymm15" ::: "xmm0", "xmm15", "memory");
}

// Clock estimate: a chain of dependent 64-bit integer multiplies, 3 cycles each on the cores
// compared here (AMD Zen 5, Intel Raptor Cove) and every x86-64 core of the last decade. (A chain
// of `add reg, imm` is no clock: Golden Cove and later fold such adds at rename, seen here at
// "8.8 GHz".) Returns GHz over a window of about `ms` milliseconds.
double ghz_sample(double ms) {
  const long n = 3000000;  // multiplies per block, ~3 ms at 3 GHz
  std::uint64_t x = 1;
  long blocks = 0;
  const auto t0 = Clock::now();
  double s = 0;
  do {
    for (long i = 0; i < n; i += 10) {
      __asm__ volatile(
          "imul %0, %0\n\timul %0, %0\n\timul %0, %0\n\timul %0, %0\n\timul %0, %0\n\t"
          "imul %0, %0\n\timul %0, %0\n\timul %0, %0\n\timul %0, %0\n\timul %0, %0"
          : "+r"(x));
    }
    ++blocks;
    s = std::chrono::duration<double>(Clock::now() - t0).count();
  } while (s * 1e3 < ms);
  return 3.0 * static_cast<double>(n) * static_cast<double>(blocks) / s / 1e9;
}

double ghz_estimate() {
  double best = 0;
  for (int r = 0; r < 5; ++r) {
    const double g = ghz_sample(40);
    if (g > best) best = g;
  }
  return best;
}

// Throughput instead of latency: four independent multiply chains, one multiply per cycle when the
// core is the thread's alone. A latency-bound chain (ghz_sample) leaves most of the core idle and
// hardly notices a busy sibling hyperthread; this one does. Returns multiplies per ns.
double mul_throughput_sample(double ms) {
  const long n = 3000000;
  std::uint64_t a = 1, b = 1, c = 1, d = 1;
  long blocks = 0;
  const auto t0 = Clock::now();
  double s = 0;
  do {
    for (long i = 0; i < n; i += 8) {
      __asm__ volatile(
          "imul %0, %0\n\timul %1, %1\n\timul %2, %2\n\timul %3, %3\n\t"
          "imul %0, %0\n\timul %1, %1\n\timul %2, %2\n\timul %3, %3"
          : "+r"(a), "+r"(b), "+r"(c), "+r"(d));
    }
    ++blocks;
    s = std::chrono::duration<double>(Clock::now() - t0).count();
  } while (s * 1e3 < ms);
  return static_cast<double>(n) * static_cast<double>(blocks) / s / 1e9;
}

// Legacy SSE (this file is built for baseline x86-64): 8 independent chains through one register;
// each chain starts with a load, as compiled code reuses registers, so with clean upper halves the
// loads break the chains and the core overlaps them; with dirty upper halves each load waits for
// the register's previous value and the 8 chains run one after another.
__attribute__((noinline)) double sse_loop_ns(long iters) {
  alignas(16) static float in[8][4] = {{1.0001f, 1, 1, 1}, {1, 1.0001f, 1, 1}, {1, 1, 1.0001f, 1}, {1, 1, 1, 1.0001f},
                                       {1.0001f, 1, 1, 1}, {1, 1.0001f, 1, 1}, {1, 1, 1.0001f, 1}, {1, 1, 1, 1.0001f}};
  alignas(16) static float out[8][4];
  const auto t0 = Clock::now();
  for (long i = 0; i < iters; ++i) {
    __asm__ volatile(
        "movaps   0(%0), %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  addps %%xmm0, %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  movaps %%xmm0,   0(%1)\n\t"
        "movaps  16(%0), %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  addps %%xmm0, %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  movaps %%xmm0,  16(%1)\n\t"
        "movaps  32(%0), %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  addps %%xmm0, %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  movaps %%xmm0,  32(%1)\n\t"
        "movaps  48(%0), %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  addps %%xmm0, %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  movaps %%xmm0,  48(%1)\n\t"
        "movaps  64(%0), %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  addps %%xmm0, %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  movaps %%xmm0,  64(%1)\n\t"
        "movaps  80(%0), %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  addps %%xmm0, %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  movaps %%xmm0,  80(%1)\n\t"
        "movaps  96(%0), %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  addps %%xmm0, %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  movaps %%xmm0,  96(%1)\n\t"
        "movaps 112(%0), %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  addps %%xmm0, %%xmm0\n\t  mulps %%xmm0, %%xmm0\n\t  movaps %%xmm0, 112(%1)\n\t"
        :
        : "r"(&in[0][0]), "r"(&out[0][0])
        : "xmm0", "memory");
  }
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  return s * 1e9 / static_cast<double>(iters);
}

double best_sse_ns() {
  double best = 1e30;
  for (int r = 0; r < 5; ++r) {
    const double t = sse_loop_ns(2000000);
    if (t < best) best = t;
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::strcmp(argv[1], "--ghz") == 0) {
    // --ghz COUNT MS: COUNT clock samples of MS milliseconds each: min, median, max, and all of them.
    const int count = std::atoi(argv[2]);
    const double ms = std::atof(argv[3]);
    std::vector<double> g;
    for (int i = 0; i < count; ++i) g.push_back(ghz_sample(ms));
    std::vector<double> sorted = g;
    std::sort(sorted.begin(), sorted.end());
    std::printf("ghz min %.3f median %.3f max %.3f (%d x %.0f ms):", sorted.front(), sorted[sorted.size() / 2], sorted.back(), count, ms);
    for (double v : g) std::printf(" %.2f", v);
    std::printf("\n");
    return 0;
  }
  if (argc == 4 && std::strcmp(argv[1], "--tput") == 0) {
    // --tput COUNT MS: COUNT samples of the multiply throughput (per ns) and of the legacy-SSE loop
    // (ns per iteration, state cleaned first where the CPU has AVX): min, median, max of each.
    const int count = std::atoi(argv[2]);
    const double ms = std::atof(argv[3]);
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx")) vzeroupper();
    std::vector<double> m, q;
    for (int i = 0; i < count; ++i) {
      m.push_back(mul_throughput_sample(ms));
      q.push_back(sse_loop_ns(static_cast<long>(ms * 1e6 / 20)));
    }
    std::sort(m.begin(), m.end());
    std::sort(q.begin(), q.end());
    std::printf("mul_per_ns min %.3f median %.3f max %.3f; sse_ns_per_iter min %.2f median %.2f max %.2f\n", m.front(), m[m.size() / 2],
                m.back(), q.front(), q[q.size() / 2], q.back());
    return 0;
  }
  // First thing: the state the process was handed.
  g_xinuse = have_xgetbv1();
  const double sse_as_found = best_sse_ns();
  const std::uint64_t x_start = g_xinuse ? xinuse() : 0;

  char brand[49] = {0};
  unsigned r[4];
  for (unsigned k = 0; k < 3; ++k) {
    __get_cpuid(0x80000002u + k, &r[0], &r[1], &r[2], &r[3]);
    std::memcpy(brand + 16 * k, r, 16);
  }
  __builtin_cpu_init();
  g_avx = __builtin_cpu_supports("avx");
  std::printf("kestrel_cpu_probe\n  cpu: %s\n  avx %d, avx2 %d, fma %d, avx512f %d (the batch kernel's dispatch: %s copy)\n", brand, g_avx,
              __builtin_cpu_supports("avx2"), __builtin_cpu_supports("fma"), __builtin_cpu_supports("avx512f"),
              __builtin_cpu_supports("avx2") ? "AVX2" : "baseline SSE2");
  std::printf("  XINUSE at main() entry: 0x%03llx\n", static_cast<unsigned long long>(x_start));
  print_xinuse("now (after printf)");
  std::printf("  clock estimate (dependent integer multiplies, best of 5 x 40 ms): %.2f GHz\n", ghz_estimate());
  std::printf("  legacy-SSE loop, state as the process found it: %.2f ns/iter\n", sse_as_found);
  if (!g_avx) return 0;

  vzeroupper();
  print_xinuse("after vzeroupper");
  const double clean = best_sse_ns();
  print_xinuse("after the SSE loop (clean)");
  dirty_upper();
  print_xinuse("after writing ymm15's upper half");
  const double dirty = best_sse_ns();
  print_xinuse("after the SSE loop (dirty)");
  vzeroupper();
  (void)syscall(SYS_getpid);
  print_xinuse("after vzeroupper, then a getpid syscall");
  const double after_syscall = best_sse_ns();
  vzeroupper();
  {
    // A page fault on a fresh page.
    char* p = static_cast<char*>(mmap(nullptr, 1 << 20, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0));
    vzeroupper();
    p[4096 * 7] = 1;
    print_xinuse("after vzeroupper, then a page fault");
    munmap(p, 1 << 20);
  }
  vzeroupper();
  usleep(1000);
  print_xinuse("after vzeroupper, then usleep(1000)");
  {
    // Does the state turn dirty on its own while the process computes (timer interrupts,
    // preemption, a sandbox's signals)? 300 ms of short SSE loops, XINUSE read after each.
    vzeroupper();
    long checks = 0, dirty_seen = 0;
    const auto t0 = Clock::now();
    while (std::chrono::duration<double>(Clock::now() - t0).count() < 0.3) {
      (void)sse_loop_ns(64);
      ++checks;
      if (g_xinuse && (xinuse() & 0x44u)) {
        ++dirty_seen;
        vzeroupper();
      }
    }
    std::printf("  300 ms of computing after vzeroupper: %ld checks, found dirty %ld times\n", checks, dirty_seen);
  }
  {
    std::uint64_t x_thread = 0;
    double t_thread = 0;
    std::thread th([&] {
      x_thread = g_xinuse ? xinuse() : 0;
      t_thread = best_sse_ns();
    });
    th.join();
    std::printf("  a new std::thread: XINUSE at entry 0x%03llx, legacy-SSE loop %.2f ns/iter before any vzeroupper\n",
                static_cast<unsigned long long>(x_thread), t_thread);
  }
  std::printf("  legacy-SSE loop ns/iter: clean %.2f, dirty upper halves %.2f (x%.2f), after a syscall %.2f\n", clean, dirty,
              dirty / clean, after_syscall);
  return 0;
}
