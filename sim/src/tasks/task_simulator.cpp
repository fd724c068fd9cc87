// The one place that turns a task's needs into a Simulator on a backend (task_support.hpp): what
// each backend needs to carry a one-robot multirotor task, so that the tasks themselves are
// written once over the Simulator interface.
#include <algorithm>
#include <string>

#include "kestrel/sim/task.hpp"
#include "task_support.hpp"

namespace kestrel::sim::task_support {

namespace {

constexpr int kPlanarDefaultLidarBeams = 128;

bool image_fits(const RangeImage& img, int rows, int cols) {
  return img.height == 1 ? img.width >= rows * cols : img.height >= rows && img.width >= cols;
}

}  // namespace

std::unique_ptr<Simulator> make_task_simulator(const WorldConfig& config, Backend backend, const TaskNeeds& needs,
                                               std::string& error) {
  const bool planar = backend == Backend::planar;
  const std::string pre = planar ? "simulator planar: task " + needs.id + ": " : needs.prefix;
  if (config.robot.robots_per_env != 1) {
    error = pre + "needs robots_per_env = 1";
    return nullptr;
  }
  WorldConfig wc = config;
  const int cells = needs.image_rows * needs.image_cols;
  if (planar) {
    const bool ground = config.simulator.vehicle == PlanarVehicle::ground_vehicle ||
                        (config.simulator.vehicle == PlanarVehicle::automatic && config.robot.kind == robots::RobotKind::ground_vehicle);
    if (ground) {
      error = pre + "flies the fixed-altitude multirotor; the ground vehicle's actions are [speed, steering] (use a "
                    "multirotor robot, e.g. base_quadrotor, or simulator: rigid)";
      return nullptr;
    }
    wc.simulator.backend = "planar";
    wc.simulator.vehicle = PlanarVehicle::multirotor;
    wc.robot.sensors.clear();  // 3-D ray sensors: the planar backend has the 2-D lidar instead
    if (needs.image) {
      if (wc.simulator.lidar_beams == 0) wc.simulator.lidar_beams = std::max(kPlanarDefaultLidarBeams, cells);
      if (wc.simulator.lidar_beams < cells) {
        error = pre + "simulator.lidar_beams (" + std::to_string(wc.simulator.lidar_beams) + ") must be at least the " +
                std::to_string(cells) + " pooled sectors of the observation (" + std::to_string(needs.image_rows) + " x " +
                std::to_string(needs.image_cols) + ")";
        return nullptr;
      }
    }
  } else if (needs.image) {
    bool ray = false;
    for (const SensorConfig& sc : config.robot.sensors) ray = ray || sc.kind != SensorKind::imu;
    if (!ray) {
      error = pre + "needs a ray sensor (lidar, ToF or camera) on the robot for its image observation, e.g. "
                    "`sensors: [vl53l5cx]`";
      return nullptr;
    }
  }
  std::unique_ptr<Simulator> s = make_simulator(wc, backend, error);
  if (!s) return nullptr;
  if (needs.image) {
    const RangeImage img = s->range_image(0, 0);
    if (!image_fits(img, needs.image_rows, needs.image_cols)) {
      error = pre + "the sensor image (" + std::to_string(img.height) + " x " + std::to_string(img.width) +
              ") is smaller than the pool grid (" + std::to_string(needs.image_rows) + " x " + std::to_string(needs.image_cols) + ")";
      return nullptr;
    }
  }
  return s;
}

void pool_image(const RangeImage& img, int rows, int cols, float* out) {
  if (img.height == 1) min_pool_image(img, 1, rows * cols, out);
  else min_pool_image(img, rows, cols, out);
}

}  // namespace kestrel::sim::task_support
