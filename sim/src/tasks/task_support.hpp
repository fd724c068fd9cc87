// What the tasks share besides the Task base (sim/task.hpp): the yaw-only vehicle frame, and the
// one place that turns a task's needs into a Simulator on a given backend (task_simulator.cpp).
#pragma once

#include <cmath>
#include <memory>
#include <string>

#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/config.hpp"
#include "kestrel/sim/simulator.hpp"

namespace kestrel::sim::task_support {

/// Yaw of the yaw-only vehicle frame (atan2 form of Aerial Gym's get_euler_xyz).
inline real yaw_of(const Quat& q) {
  const real x = q.x(), y = q.y(), z = q.z(), w = q.w();
  return std::atan2(2 * (w * z + x * y), w * w + x * x - y * y - z * z);
}

/// World-frame vector expressed in the vehicle frame (rotation by -yaw about z).
inline Vec3 world_to_vehicle(const Quat& q, const Vec3& v_w) {
  const real yaw = yaw_of(q), c = std::cos(yaw), s = std::sin(yaw);
  return Vec3(c * v_w[0] + s * v_w[1], -s * v_w[0] + c * v_w[1], v_w[2]);
}

/// What a task asks of the backend it runs on.
struct TaskNeeds {
  std::string id;              // the task id, for messages
  std::string prefix;          // message prefix ("navigation_task: ", "custom task 'x': ")
  bool image = false;          // reads a ray-sensor image (range image 0 of robot 0)
  int image_rows = 0, image_cols = 0;  // its pool grid (a one-row image pools into rows * cols sectors)
};

/// Builds the Simulator a task runs on, on `backend`: one robot per environment; on planar the
/// fixed-altitude multirotor (the ground vehicle is refused: its actions are [speed, steering],
/// not the tasks' multirotor commands), the robot's 3-D sensors dropped and the 2-D lidar as
/// its image (128 beams when the scenario gives none, at least the pooled sectors); on rigid the
/// robot's first ray sensor, at least as large as the pool grid. nullptr and a message naming the
/// task, the backend and the alternative otherwise.
std::unique_ptr<Simulator> make_task_simulator(const WorldConfig& config, Backend backend, const TaskNeeds& needs,
                                               std::string& error);

/// Range pooling of image 0 of robot env: a grid image into rows x cols cells, a one-row image
/// (a horizontal scan) into one row of rows * cols sectors (min_pool_ranges' rule on each cell).
void pool_image(const RangeImage& img, int rows, int cols, float* out);

}  // namespace kestrel::sim::task_support
