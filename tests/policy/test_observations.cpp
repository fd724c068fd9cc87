// The observation builders a trained policy sees in training and in the firmware
// (policy/observations.hpp): navigation_task's state part against hand-computed values, and the
// image pooling over a strided (column-reversed) image, on the host and the emulated MCU.
#include <limits>

#include "kestrel/policy/observations.hpp"
#include "ktest.hpp"

using namespace kestrel;
namespace pl = kestrel::policy;

KTEST(PolicyObservations, NavigationStatePart) {
  const float e_v[3] = {3, 0, 4}, v_b[3] = {1, 2, 3}, w_b[3] = {-1, -2, -3}, act[4] = {0.5f, -0.5f, 0.25f, 1};
  float o[pl::kNavigationStateObsDim];
  pl::navigation_state_observation(e_v, 0.1f, -0.2f, v_b, w_b, act, o);
  KEXPECT_EQ(o[0], 0.6f);
  KEXPECT_EQ(o[1], 0.0f);
  KEXPECT_EQ(o[2], 0.8f);
  KEXPECT_EQ(o[3], 5.0f);
  KEXPECT_EQ(o[4], 0.1f);
  KEXPECT_EQ(o[5], -0.2f);
  KEXPECT_EQ(o[6], 0.0f);
  for (int k = 0; k < 3; ++k) {
    KEXPECT_EQ(o[7 + k], v_b[k]);
    KEXPECT_EQ(o[10 + k], w_b[k]);
  }
  for (int k = 0; k < 4; ++k) KEXPECT_EQ(o[13 + k], act[k]);
  const float at_goal[3] = {0, 0, 0};
  pl::navigation_state_observation(at_goal, 0, 0, v_b, w_b, act, o);
  KEXPECT_EQ(o[0], 0.0f);  // no direction at the goal, no division by zero
  KEXPECT_EQ(o[3], 0.0f);
}

KTEST(PolicyObservations, MinPoolingOfAStridedImage) {
  // 2 x 4 image stored row-major; read with the columns reversed (col_step -1), as the planar
  // lidar row is. Ranges over max 4 m; a NaN and a negative value are no return.
  const real nan = std::numeric_limits<real>::quiet_NaN();
  const real stored[8] = {4, 1, 3, nan, 2, -1, 8, 0.5_r};
  float out[4];
  pl::min_pool_ranges(stored + 3, 2, 4, 4, -1, 4, 2, 2, out);
  // Read image rows: [nan, 3, 1, 4] and [0.5, 8, -1, 2]; cells of 1 x 2.
  KEXPECT_EQ(out[0], 0.75f);   // min(nan, 3) / 4
  KEXPECT_EQ(out[1], 0.25f);   // min(1, 4) / 4
  KEXPECT_EQ(out[2], 0.125f);  // min(0.5, 8) / 4
  KEXPECT_EQ(out[3], 0.5f);    // min(-1 ignored, 2) / 4
  float all[1];
  pl::min_pool_ranges(stored, 2, 4, 4, 1, 4, 1, 1, all);
  KEXPECT_EQ(all[0], 0.125f);
  const real far[2] = {9, nan};  // beyond the range, no return: 1
  pl::min_pool_ranges(far, 1, 2, 2, 1, 4, 1, 1, all);
  KEXPECT_EQ(all[0], 1.0f);
}

KTEST(PolicyObservations, FrameHistory) {
  // Two earlier frames 2 steps apart: 5 slots. Frame t holds {t, 10 t}.
  constexpr int kCells = 2, kFrames = 2, kLag = 2;
  const int span = pl::frame_history_span(kFrames, kLag);
  KEXPECT_EQ(span, 5);
  float ring[5 * kCells];
  const float first[kCells] = {0.0f, 0.0f};
  pl::frame_history_fill(ring, span, kCells, first);
  int head = 0;
  float out[kFrames * kCells];
  for (int t = 1; t <= 12; ++t) {
    head = pl::frame_history_advance(span, head);
    KEXPECT_TRUE(head >= 0 && head < span);
    ring[head * kCells] = static_cast<float>(t);
    ring[head * kCells + 1] = 10.0f * static_cast<float>(t);
    KEXPECT_EQ(pl::frame_history_at(ring, span, kCells, head, 0)[0], static_cast<float>(t));
    pl::frame_history_write(ring, span, kCells, head, kFrames, kLag, out);
    // lag and 2 lag steps before, or the first frame (0) before the history began.
    for (int j = 1; j <= kFrames; ++j) {
      const float want = t - j * kLag > 0 ? static_cast<float>(t - j * kLag) : 0.0f;
      KEXPECT_EQ(out[(j - 1) * kCells], want);
      KEXPECT_EQ(out[(j - 1) * kCells + 1], 10.0f * want);
    }
  }
}

KTEST(PolicyObservations, ProximityCells) {
  // Range cells of a 10 m sensor as proximities with scale 0.5 m: contact 1, 0.5 m reads 0.5,
  // 2 m reads 0.2, no return (10 m) 1 / 21.
  float cells[4] = {0.0f, 0.05f, 0.2f, 1.0f};
  pl::proximity_from_range_cells(cells, 4, 10.0f, 0.5f);
  KEXPECT_EQ(cells[0], 1.0f);
  KEXPECT_NEAR(cells[1], 0.5f, 1e-7f);
  KEXPECT_NEAR(cells[2], 0.2f, 1e-7f);
  KEXPECT_NEAR(cells[3], 1.0f / 21.0f, 1e-7f);
}
