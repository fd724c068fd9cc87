// The 8 x 8 multizone ToF (VL53L5CX preset) scanning a small scene: a floor plane, a box wall, a
// capsule post and a sphere. Every zone is checked against an independent analytic answer; on the
// MCU the scan's instruction count is printed (deterministic under qemu -icount; not asserted).
#include <cmath>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sensors/ray_sensor.hpp"
#include "ktest.hpp"

#if defined(KESTREL_PLATFORM_CORTEX_M) || defined(KESTREL_PLATFORM_RISCV)
#include "kestrel/platform/board.hpp"
#include "kestrel/platform/console.hpp"
#endif

using namespace kestrel;
using namespace kestrel::sensors;

namespace {

SceneStorage<8> g_tof_storage;
real g_tof_dirs[3 * 64], g_tof_scale[64], g_tof_range[64];
std::int32_t g_tof_seg[64];

}  // namespace

KTEST(SensorTof, Vl53l5cxScanOfSmallScene) {
  Scene s(g_tof_storage);
  const Quat id = Quat::Identity();
  KASSERT_EQ(static_cast<int>(s.add(Shape::plane(), Vec3(0, 0, -0.6_r), id, 1)), 0);         // floor 0.6 m below
  KASSERT_EQ(static_cast<int>(s.add(Shape::box(0.1_r, 2, 2), Vec3(2.1_r, 0, 0), id, 2)), 0);  // wall at x = 2
  KASSERT_EQ(static_cast<int>(s.add(Shape::capsule(0.1_r, 0.5_r), Vec3(1, 0.3_r, 0), id, 3)), 0);
  KASSERT_EQ(static_cast<int>(s.add(Shape::sphere(0.15_r), Vec3(1.5_r, -0.4_r, 0.3_r), id, 4)), 0);
  Status st = Status::invalid_argument;
  KEXPECT_NO_HEAP(st = s.build());
  KASSERT_EQ(static_cast<int>(st), 0);
  const LidarParams p = lidar_preset_vl53l5cx();
  RayTable t{g_tof_dirs, g_tof_scale, 64, 0, 0};
  KASSERT_EQ(static_cast<int>(lidar_rays(p, t)), 0);
  SensorPose pose;  // at the origin, looking along +x
  SensorOutput out;
  out.range = g_tof_range;
  out.segmentation = g_tof_seg;
  KEXPECT_NO_HEAP(st = render(s, pose, t, p.range, false, out));
  KASSERT_EQ(static_cast<int>(st), 0);
  int counts[5] = {0, 0, 0, 0, 0};
  for (std::uint32_t i = 0; i < 64; ++i) {
    const real* d = &g_tof_dirs[3 * i];
    // Independent answer: nearest of the analytic candidates.
    real best = 1000;
    int seg = -1;
    auto take = [&](real tt, int sg) {
      if (tt > 0 && tt < best) {
        best = tt;
        seg = sg;
      }
    };
    if (d[2] < 0) take(-0.6_r / d[2], 1);
    {
      const real tt = 2 / d[0];
      const real y = tt * d[1], z = tt * d[2];
      if (std::fabs(y) <= 2 && std::fabs(z) <= 2) take(tt, 2);
    }
    for (int c = 0; c < 3; ++c) {  // capsule = cylinder + two spheres about (1, 0.3, z)
      const real cz = c == 0 ? 0 : (c == 1 ? -0.5_r : 0.5_r);
      const real o[3] = {-1, -0.3_r, -cz};
      if (c == 0) {
        const real a = d[0] * d[0] + d[1] * d[1], b = o[0] * d[0] + o[1] * d[1], cc = o[0] * o[0] + o[1] * o[1] - 0.01_r;
        const real disc = b * b - a * cc;
        if (disc >= 0) {
          const real tt = (-b - std::sqrt(disc)) / a;
          if (std::fabs(tt * d[2]) <= 0.5_r) take(tt, 3);
        }
      } else {
        const real b = o[0] * d[0] + o[1] * d[1] + o[2] * d[2];
        const real cc = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - 0.01_r;
        if (b * b - cc >= 0) take(-b - std::sqrt(b * b - cc), 3);
      }
    }
    {
      const real o[3] = {-1.5_r, 0.4_r, -0.3_r};
      const real b = o[0] * d[0] + o[1] * d[1] + o[2] * d[2];
      const real cc = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - 0.0225_r;
      if (b * b - cc >= 0) take(-b - std::sqrt(b * b - cc), 4);
    }
    // Beyond max_range: no return (far_out_of_range_value, -1 for this preset) and no segment.
    if (best > p.range.max_range) {
      seg = -1;
      best = p.range.far_out_of_range_value;
    }
    KEXPECT_EQ(g_tof_seg[i], seg);
    KEXPECT_NEAR(g_tof_range[i], best, 2e-5);
    if (seg >= 0) ++counts[seg];
  }
  KEXPECT_GT(counts[1], 0);
  KEXPECT_GT(counts[2], 0);
  KEXPECT_GT(counts[3], 0);

#if defined(KESTREL_PLATFORM_CORTEX_M) || defined(KESTREL_PLATFORM_RISCV)
  namespace board = kestrel::platform::board;
  board::systick_start();
  auto scan = [&] { (void)render(s, pose, t, p.range, false, out); };
  std::uint64_t best_ticks = ~0ull;
  for (int k = 0; k < 5; ++k) {
    const std::uint64_t ticks = board::measure_ticks(scan);
    best_ticks = ticks < best_ticks ? ticks : best_ticks;
  }
  kestrel::platform::print("  ToF 8x8 scan (4 objects): ");
  kestrel::platform::print_uint(board::ticks_to_instructions(best_ticks));
  kestrel::platform::println(" instructions");
#endif
}
