// kestrel._core: Python bindings of the simulation harness (sim/) with nanobind.
//
// Why nanobind (not pybind11): a bound call costs a few hundred nanoseconds instead of about a
// microsecond (the budget is <= 3 us per step call at one environment), and nb::ndarray
// returns numpy arrays that view C++ memory with an owner object, which is how every buffer here
// reaches Python without a copy.
//
// Zero-copy: a Task's observations, rewards, terminations, truncations and final observations are
// numpy arrays over the task's own buffers (sim/task.hpp: rewritten in place by every step), with
// the Python Task object as their owner, so the arrays keep the task alive and the data pointer
// never changes for the task's lifetime. Actions are read in place from a C-contiguous float32
// array (checked: dtype, shape, contiguity, finiteness; a bad array raises TypeError/ValueError
// naming the argument and what is allowed, and nothing is stepped). The GIL is released while the
// world steps on its threads.
//
// Nothing in sim/ or the core depends on this file.
#include <box2d/b2_block_allocator.h>
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/unique_ptr.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "kestrel/allocation/presets.hpp"
#include "kestrel/robots/multirotor.hpp"
#include "kestrel/sim/limits.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/pick_place_camera.hpp"
#include "kestrel/sim/pick_place_task.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/rigid_backend.hpp"
#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/simulator.hpp"
#include "kestrel/sim/task.hpp"
#include "kestrel/sim/terrain.hpp"
#include "kestrel/sim/world.hpp"
#include "kestrel/sim/world_model.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using kestrel::real;
namespace ks = kestrel::sim;

namespace {

static_assert(sizeof(bool) == 1, "flags are viewed as numpy bool over 0/1 bytes");

template <class T>
using Array1 = nb::ndarray<nb::numpy, T, nb::ndim<1>, nb::c_contig>;
template <class T>
using Array2 = nb::ndarray<nb::numpy, T, nb::ndim<2>, nb::c_contig>;

std::string dtype_name(const nb::dlpack::dtype& d) {
  const char* base = d.code == static_cast<std::uint8_t>(nb::dlpack::dtype_code::Float)  ? "float"
                     : d.code == static_cast<std::uint8_t>(nb::dlpack::dtype_code::Int)  ? "int"
                     : d.code == static_cast<std::uint8_t>(nb::dlpack::dtype_code::UInt) ? "uint"
                     : d.code == static_cast<std::uint8_t>(nb::dlpack::dtype_code::Bool) ? "bool"
                                                                                          : "complex";
  if (d.code == static_cast<std::uint8_t>(nb::dlpack::dtype_code::Bool)) return base;
  return std::string(base) + std::to_string(d.bits);
}

std::string shape_text(const nb::ndarray<>& a) {
  std::string s = "(";
  for (std::size_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

/// Checks an action array: float32 (or `real`), C-contiguous, shape (rows, cols), on the CPU, finite.
/// Returns the data pointer (no copy). Raises TypeError / ValueError naming `what`.
template <class T>
const T* checked_actions(nb::handle h, std::size_t rows, std::size_t cols, const char* what,
                         const char* dims = "(num_envs, action_dim)") {
  nb::ndarray<> a;
  const char* want = sizeof(T) == 4 ? "float32" : "float64";
  if (!nb::try_cast(h, a, false))
    throw nb::type_error((std::string(what) + ": expected a numpy " + want + " array of shape (" + std::to_string(rows) + ", " +
                          std::to_string(cols) + "), got an object of type " +
                          nb::type_name(h.type()).c_str())
                             .c_str());
  if (a.device_type() != nb::device::cpu::value)
    throw nb::type_error((std::string(what) + ": expected an array in CPU memory").c_str());
  if (a.dtype() != nb::dtype<T>())
    throw nb::type_error((std::string(what) + ": expected dtype " + want + ", got " + dtype_name(a.dtype()) +
                          " (convert with .astype(numpy." + want + "))")
                             .c_str());
  if (a.ndim() != 2 || a.shape(0) != rows || a.shape(1) != cols)
    throw nb::value_error((std::string(what) + ": expected shape (" + std::to_string(rows) + ", " + std::to_string(cols) +
                           ") = " + dims + ", got " + shape_text(a))
                              .c_str());
  if (rows * cols > 0 && (a.stride(1) != 1 || a.stride(0) != static_cast<std::int64_t>(cols)))
    throw nb::value_error(
        (std::string(what) + ": expected a C-contiguous array (use numpy.ascontiguousarray), got strides (" +
         std::to_string(a.stride(0)) + ", " + std::to_string(a.stride(1)) + ") elements")
            .c_str());
  const T* p = static_cast<const T*>(a.data());
  for (std::size_t i = 0; i < rows * cols; ++i)
    if (!std::isfinite(p[i]))
      throw nb::value_error((std::string(what) + ": expected finite values, got " + std::to_string(static_cast<double>(p[i])) +
                             " at [" + std::to_string(i / cols) + ", " + std::to_string(i % cols) + "]")
                                .c_str());
  return p;
}

// ---- scenario config -----------------------------------------------------------------------------

struct KConfig {
  ks::WorldConfig cfg;
  std::string source;
};

KConfig load_string(const std::string& text, const std::string& name, const std::string& base_dir) {
  KConfig c;
  std::string err;
  if (!ks::load_scenario_string(text, name, base_dir, c.cfg, err)) throw nb::value_error(("scenario " + err).c_str());
  c.source = name;
  return c;
}

KConfig load_file(const std::string& path) {
  KConfig c;
  std::string err;
  if (!ks::load_scenario_file(path, c.cfg, err)) throw nb::value_error(("scenario " + err).c_str());
  c.source = path;
  return c;
}

ks::Backend pick_backend(const ks::WorldConfig& cfg, const std::string& backend) {
  ks::Backend b = ks::Backend::rigid;
  std::string err;
  if (backend.empty()) {
    if (!ks::resolve_backend(cfg, b, err)) throw nb::value_error(err.c_str());
  } else if (!ks::backend_from_name(backend, b)) {
    throw nb::value_error(("backend: expected one of rigid, planar (or None for the scenario's), got \"" + backend + "\"").c_str());
  }
  return b;
}

// ---- Task ------------------------------------------------------------------------------------------

struct KTask {
  std::unique_ptr<ks::Task> task;
  ks::WorldConfig cfg;

  ks::Task& t() { return *task; }
  std::size_t n() const { return static_cast<std::size_t>(task->num_envs()); }
  std::size_t od() const { return static_cast<std::size_t>(task->obs_dim()); }
  std::size_t ad() const { return static_cast<std::size_t>(task->action_dim()); }
};

/// so101_pick_place's world of environment env (a clear error for any other task or env).
const ks::PickPlaceWorld* pick_place_env(KTask& p, int env) {
  if (env < 0 || env >= p.t().num_envs())
    throw nb::value_error(("env: expected 0.." + std::to_string(p.t().num_envs() - 1) + " (got " + std::to_string(env) + ")").c_str());
  const ks::PickPlaceWorld* w = ks::pick_place_world(p.t(), env);
  if (w == nullptr)
    throw nb::value_error(("task " + std::string(p.t().name()) + ": cameras and the scene state are so101_pick_place's").c_str());
  return w;
}

std::unique_ptr<KTask> make_task(const KConfig& c, const std::string& backend) {
  if (!ks::is_rl_task(c.cfg.task.name))
    throw nb::value_error(("task: unknown task id \"" + c.cfg.task.name + "\"; registered task ids: " + ks::rl_task_ids_joined()).c_str());
  const ks::Backend b = pick_backend(c.cfg, backend);
  std::string err;
  auto p = std::make_unique<KTask>();
  p->cfg = c.cfg;
  {
    nb::gil_scoped_release release;
    p->task = ks::make_task(c.cfg, b, err);
  }
  if (!p->task) throw nb::value_error((c.source + ": " + err).c_str());
  p->task->set_keep_final_observations(true);
  return p;
}

nb::dict infos_dict(const ks::TaskInfos& in) {
  nb::dict d;
  d["steps"] = in.steps;
  d["episodes"] = in.episodes;
  d["terminations"] = in.terminations;
  d["truncations"] = in.truncations;
  d["crashes"] = in.crashes;
  d["successes"] = in.successes;
  d["fallback_episodes"] = in.fallback_episodes;
  d["episode_reward_sum"] = in.episode_reward_sum;
  d["mean_episode_reward"] = in.mean_episode_reward();
  d["success_rate"] = in.success_rate();
  d["curriculum_level"] = in.curriculum_level;
  d["mean_terrain_level"] = in.mean_terrain_level;
  d["curriculum_changes"] = in.curriculum_changes;
  return d;
}

// The run summary `kestrel run` prints (sim/summary.hpp WorldSummary), for per-run tables (kestrel.cluster's
// sweeps) computed by the same C++ as the CLI's.
nb::dict summary_dict(const ks::WorldSummary& s) {
  nb::dict d;
  d["env_steps"] = s.env_steps;
  d["crashes"] = s.crashes;
  d["resets"] = s.resets;
  d["timeouts"] = s.timeouts;
  d["out_of_bounds"] = s.out_of_bounds;
  d["episodes_done"] = s.episodes_done;
  d["successes"] = s.successes;
  d["real_episodes"] = s.real_episodes();
  d["placements"] = s.placements;
  d["placement_fallbacks"] = s.placement_fallbacks;
  d["fallback_episodes"] = s.fallback_episodes;
  d["mean_tracking_error_m"] = s.mean_tracking_error_m;
  d["final_mean_distance_m"] = s.final_mean_distance_m;
  d["episode_end_distance_m"] = s.episode_end_distance_m;
  d["fault_bits"] = s.fault_bits;
  d["reset_errors"] = s.reset_errors;
  return d;
}

// ---- Simulator ---------------------------------------------------------------------------------------

// A Python viewer (kestrel.viewer.Viewer or any object with its set_viewer_camera(position,
// lookat) and draw_debug_vis(height_samples, contacts)) behind the Simulator's viewer hooks.
struct PyViewerHooks final : ks::Simulator::ViewerHooks {
  nb::object viewer;
  void on_viewer_request(const ks::Simulator::ViewerRequest& r) override {
    nb::gil_scoped_acquire gil;
    if (r.camera_set) {
      const kestrel::Vec3 &p = r.camera_position_w, &l = r.camera_lookat_w;
      viewer.attr("set_viewer_camera")(nb::make_tuple(p[0], p[1], p[2]), nb::make_tuple(l[0], l[1], l[2]));
    }
    viewer.attr("draw_debug_vis")(r.debug_height_samples, r.debug_contacts);
  }
};

struct KSimulator {
  std::unique_ptr<ks::Simulator> owned;  // null for a Task's simulator (Task.simulator), which the Task owns
  ks::Simulator* sim = nullptr;
  std::unique_ptr<PyViewerHooks> viewer;  // attach_viewer's adapter
  std::size_t robots() const { return static_cast<std::size_t>(sim->num_robots()); }
  ~KSimulator() {
    if (viewer && sim != nullptr) sim->set_viewer(nullptr);
  }
  KSimulator(std::unique_ptr<ks::Simulator> o, ks::Simulator* s) : owned(std::move(o)), sim(s) {}
  KSimulator(const KSimulator&) = delete;
  KSimulator& operator=(const KSimulator&) = delete;
  KSimulator(KSimulator&&) = default;
  KSimulator& operator=(KSimulator&&) = default;
};

// Range / segmentation images (Simulator::range_image, World::sensor_segmentation) as read-only
// numpy views: element [i, r, c] of the (num_robots, height, width) view is robot i's pixel (r, c),
// at ranges + i * robot_step + r * row_step + c * col_step (the RangeImage's own steps, so the
// planar lidar row, stored clockwise-first, is viewed with a negative column stride: no copy).
struct ImageLayout {
  const void* base = nullptr;  // robot 0's pixel (0, 0)
  std::size_t height = 0, width = 0;
  std::int64_t robot_step = 0, row_step = 0, col_step = 0;  // elements
};

void check_image_index(const ks::Simulator& sim, int k) {
  if (sim.num_range_images() == 0)
    throw nb::value_error((std::string("range image: this ") + sim.backend_name() +
                           " simulator has no range images (rigid: attach a lidar, ToF or camera through `sensors:`; "
                           "planar: set simulator.lidar_beams)")
                              .c_str());
  if (k < 0 || k >= sim.num_range_images())
    throw nb::value_error(("k: expected an image index in [0, " + std::to_string(sim.num_range_images()) + "), got " +
                           std::to_string(k))
                              .c_str());
}

/// Robot-major layout of image k; every robot's image must sit at a constant step from robot 0's
/// (both backends store them that way; checked, never assumed).
ImageLayout range_layout(const ks::Simulator& sim, int k) {
  check_image_index(sim, k);
  const ks::RangeImage i0 = sim.range_image(0, k);
  ImageLayout l{i0.ranges, static_cast<std::size_t>(i0.height), static_cast<std::size_t>(i0.width), 0, i0.row_step, i0.col_step};
  const int n = sim.num_robots();
  if (n > 1) l.robot_step = sim.range_image(1, k).ranges - i0.ranges;
  for (int i = 0; i < n; ++i) {
    const ks::RangeImage im = sim.range_image(i, k);
    if (im.ranges != i0.ranges + static_cast<std::ptrdiff_t>(i) * l.robot_step || im.height != i0.height ||
        im.width != i0.width || im.row_step != i0.row_step || im.col_step != i0.col_step)
      throw nb::value_error("range_images: this backend's images are not evenly spaced in memory; use range_image(robot, k)");
  }
  return l;
}

/// World sensor index of the k-th range image (the ray sensors in robot.sensors order, IMUs skipped).
int world_ray_sensor(const ks::World& w, int k) {
  for (int s = 0, seen = 0; s < w.num_sensors(); ++s)
    if (w.sensor_config(s).kind != ks::SensorKind::imu && seen++ == k) return s;
  return -1;
}

ImageLayout segmentation_layout(const ks::Simulator& sim, int k) {
  check_image_index(sim, k);
  const ks::World* w = ks::rigid_world(sim);
  if (w == nullptr)
    throw nb::value_error((std::string("segmentation images: the ") + sim.backend_name() +
                           " simulator renders ranges only (its 2-D lidar has no segmentation); use simulator: rigid")
                              .c_str());
  const int s = world_ray_sensor(*w, k);
  const int rpe = sim.robots_per_env();
  const std::int32_t* b = w->sensor_segmentation(0, s, 0);
  ImageLayout l{b, static_cast<std::size_t>(w->sensor_height(s)), static_cast<std::size_t>(w->sensor_width(s)), 0,
                w->sensor_width(s), 1};
  const int n = sim.num_robots();
  if (n > 1) l.robot_step = w->sensor_segmentation(1 / rpe, s, 1 % rpe) - b;
  for (int i = 0; i < n; ++i)
    if (w->sensor_segmentation(i / rpe, s, i % rpe) != b + static_cast<std::ptrdiff_t>(i) * l.robot_step)
      throw nb::value_error("segmentation_images: this world's images are not evenly spaced in memory");
  return l;
}

/// A read-only (rows x cols) view of `T` values that start at `first` and repeat every `row_bytes`
/// bytes (a member of each element of an array of structs), owned by `owner`.
template <class T>
nb::ndarray<nb::numpy, const T> strided_view(const void* first, std::size_t rows, std::size_t cols, std::size_t row_bytes,
                                             nb::handle owner) {
  const std::size_t shape[2] = {rows, cols};
  const std::int64_t strides[2] = {static_cast<std::int64_t>(row_bytes / sizeof(T)), 1};
  return nb::ndarray<nb::numpy, const T>(static_cast<const T*>(first), cols == 1 ? 1 : 2, shape, owner, strides);
}

/// The rigid World's data (sim/world_data.hpp) as numpy views without copies: what a step writes,
/// in place. The arrays are sized once, so the views stay valid while the simulator lives.
nb::dict world_data_views(const ks::Simulator& sim, nb::handle owner) {
  const ks::World* w = ks::rigid_world(sim);
  if (w == nullptr)
    throw nb::value_error((std::string("world_data: the ") + sim.backend_name() +
                           " simulator keeps its state in Box2D, not in a WorldData; use simulator: rigid (or the base_* views)")
                              .c_str());
  const ks::WorldData& d = w->data();
  const ks::WorldModel& m = w->model();
  static_assert(sizeof(kestrel::Vec3) == 3 * sizeof(kestrel::real), "Vec3 arrays are (n x 3) reals");
  static_assert(sizeof(kestrel::RigidBodyState) % sizeof(kestrel::real) == 0, "state rows are whole reals");
  const std::size_t n = d.state.size(), e = static_cast<std::size_t>(m.num_envs), sb = sizeof(kestrel::RigidBodyState);
  nb::dict out;
  out["position_w"] = strided_view<kestrel::real>(d.state[0].position_w.data(), n, 3, sb, owner);
  out["orientation_xyzw"] = strided_view<kestrel::real>(d.state[0].orientation_wb.coeffs().data(), n, 4, sb, owner);
  out["linvel_w"] = strided_view<kestrel::real>(d.state[0].linvel_w.data(), n, 3, sb, owner);
  out["angvel_b"] = strided_view<kestrel::real>(d.state[0].angvel_b.data(), n, 3, sb, owner);
  out["contact_force_w"] = strided_view<kestrel::real>(d.contact_force_w.data(), n, 3, sizeof(kestrel::Vec3), owner);
  out["contact_torque_b"] = strided_view<kestrel::real>(d.contact_torque_b.data(), n, 3, sizeof(kestrel::Vec3), owner);
  out["target_w"] = strided_view<kestrel::real>(d.target_w.data(), n, 3, sizeof(kestrel::Vec3), owner);
  out["setpoint_w"] = strided_view<kestrel::real>(d.setpoint_w.data(), n, 3, sizeof(kestrel::Vec3), owner);
  out["actions"] = strided_view<kestrel::real>(d.actions.data(), n, kestrel::kMaxActionDim, kestrel::kMaxActionDim * sizeof(kestrel::real), owner);
  out["crashed"] = strided_view<std::uint8_t>(d.crashed.data(), n, 1, 1, owner);
  out["episode_step"] = strided_view<int>(d.episode_step.data(), e, 1, sizeof(int), owner);
  out["num_obstacles"] = strided_view<int>(d.num_obstacles.data(), e, 1, sizeof(int), owner);
  out["lower_w"] = strided_view<kestrel::real>(d.lower_w.data(), e, 3, sizeof(kestrel::Vec3), owner);
  out["upper_w"] = strided_view<kestrel::real>(d.upper_w.data(), e, 3, sizeof(kestrel::Vec3), owner);
  if (m.obstacle_capacity > 0) {
    // (num_envs, capacity, 3): slot i of env e; only the first num_obstacles[e] are in use.
    const std::size_t cap = static_cast<std::size_t>(m.obstacle_capacity), ob = sizeof(ks::Obstacle);
    const std::size_t shape[3] = {e, cap, 3};
    const std::int64_t strides[3] = {static_cast<std::int64_t>(cap * ob / sizeof(kestrel::real)),
                                     static_cast<std::int64_t>(ob / sizeof(kestrel::real)), 1};
    out["obstacle_position_w"] = nb::ndarray<nb::numpy, const kestrel::real>(d.obstacles[0].shape.position_w.data(), 3, shape, owner, strides);
  }
  if (m.height_points > 0)
    out["measured_heights"] = strided_view<kestrel::real>(d.measured_heights.data(), n, static_cast<std::size_t>(m.height_points),
                                                          static_cast<std::size_t>(m.height_points) * sizeof(kestrel::real), owner);
  return out;
}

template <class T>
nb::ndarray<nb::numpy, const T, nb::ndim<3>> image_view3(const ImageLayout& l, std::size_t robots, nb::handle owner) {
  const std::size_t shape[3] = {robots, l.height, l.width};
  const std::int64_t strides[3] = {l.robot_step, l.row_step, l.col_step};
  return nb::ndarray<nb::numpy, const T, nb::ndim<3>>(static_cast<const T*>(l.base), 3, shape, owner, strides);
}

template <class T>
nb::ndarray<nb::numpy, const T, nb::ndim<2>> image_view2(const ImageLayout& l, int robot, nb::handle owner) {
  const std::size_t shape[2] = {l.height, l.width};
  const std::int64_t strides[2] = {l.row_step, l.col_step};
  return nb::ndarray<nb::numpy, const T, nb::ndim<2>>(static_cast<const T*>(l.base) + robot * l.robot_step, 2, shape, owner,
                                                       strides);
}

void check_robot(const ks::Simulator& sim, int robot) {
  if (robot < 0 || robot >= sim.num_robots())
    throw nb::value_error(("robot: expected a robot index in [0, " + std::to_string(sim.num_robots()) +
                           ") (env * robots_per_env + r), got " + std::to_string(robot))
                              .c_str());
}

template <class T>
nb::ndarray<nb::numpy, T, nb::ndim<2>, nb::c_contig> view2(const T* p, std::size_t rows, std::size_t cols, nb::handle owner) {
  return nb::ndarray<nb::numpy, T, nb::ndim<2>, nb::c_contig>(const_cast<T*>(p), {rows, cols}, owner);
}

// ---- Box2D allocation hooks ---------------------------------------------------------------------------
// sim/src/backends/planar.cpp defines b2Alloc_Default / b2Free_Default; every block it hands out from the heap
// is preceded by a 16-byte header whose first word is "MALC". b2BlockAllocator::Allocate is compiled
// in libbox2d.so and, for a size above b2_maxBlockSize, calls b2Alloc -> b2Alloc_Default through
// libbox2d's PLT: if the tag is there, the extension module's definitions took effect.
bool box2d_hooks_active() {
  b2BlockAllocator a;
  const int32 size = 4096;  // > b2_maxBlockSize (640): straight to b2Alloc
  void* p = a.Allocate(size);
  std::uint32_t tag = 0;
  std::memcpy(&tag, static_cast<unsigned char*>(p) - 16, sizeof(tag));
  a.Free(p, size);
  return tag == 0x4d414c43u;
}

template <class T>
nb::list registry_list(const ks::Registry<T>& r) {
  nb::list out;
  for (const std::string& n : r.names()) out.append(nb::make_tuple(n, r.description(n)));
  return out;
}


// ---- What the viewer and the recorder read (python/kestrel/viewer.py, record.py) ---------------------
// Copies, not views: they are read once per drawn frame or recorded step, and the obstacle slots
// of an environment are an array of structs whose shapes a viewer needs in one piece.

const ks::World& rigid_or_raise(const ks::Simulator& sim, const char* what) {
  const ks::World* w = ks::rigid_world(sim);
  if (w == nullptr)
    throw nb::value_error((std::string(what) + ": the " + sim.backend_name() +
                           " simulator keeps its obstacles and motors in Box2D, not in a WorldData; use simulator: rigid")
                              .c_str());
  return *w;
}

template <class T>
nb::ndarray<nb::numpy, T> owned_array(std::vector<T>&& v, std::initializer_list<std::size_t> shape_list) {
  auto* heap = new std::vector<T>(std::move(v));
  nb::capsule owner(heap, [](void* q) noexcept { delete static_cast<std::vector<T>*>(q); });
  std::size_t shape[4] = {0, 0, 0, 0};
  std::size_t nd = 0;
  for (std::size_t d : shape_list) shape[nd++] = d;
  return nb::ndarray<nb::numpy, T>(heap->data(), nd, shape, owner);
}

/// Range image k's rays (the viewer's point clouds, python/kestrel/viewer.py): the sensor-frame ray
/// table the World renders with, rebuilt here from the sensor's config by the same core functions
/// (sensors::lidar_rays / camera_rays, as sim/src/compile/world_model.cpp does), and the output
/// rules needed to turn a pixel back into metres along its ray. Rigid only: the planar 2-D lidar has
/// no mount or ray table.
nb::dict range_image_rays(const ks::Simulator& sim, int k) {
  check_image_index(sim, k);
  const ks::World& w = rigid_or_raise(sim, "range_image_rays");
  const int si = world_ray_sensor(w, k);
  const ks::SensorConfig& c = w.sensor_config(si);
  const bool cam = c.kind == ks::SensorKind::camera;
  const std::uint32_t h = cam ? c.camera.height : c.lidar.height, wd = cam ? c.camera.width : c.lidar.width;
  const std::size_t n = static_cast<std::size_t>(h) * wd;
  std::vector<kestrel::real> dirs(3 * n), scale(n, 1);
  kestrel::sensors::RayTable t;
  t.dirs_s = dirs.data();
  t.depth_scale = scale.data();
  t.capacity = static_cast<std::uint32_t>(n);
  const kestrel::Status st = cam ? kestrel::sensors::camera_rays(c.camera, t) : kestrel::sensors::lidar_rays(c.lidar, t);
  if (st != kestrel::Status::ok || t.height != h || t.width != wd)
    throw nb::value_error(("range_image_rays: sensor " + c.name + ": its ray pattern could not be rebuilt").c_str());
  const kestrel::sensors::RangeOutputParams& r = cam ? c.camera.range : c.lidar.range;
  std::vector<double> d3(dirs.begin(), dirs.end()), ds(scale.begin(), scale.end());
  nb::dict d;
  d["name"] = c.name;
  d["kind"] = cam ? "camera" : "lidar";
  d["dirs_s"] = owned_array(std::move(d3), {h, wd, 3});
  d["depth_scale"] = owned_array(std::move(ds), {h, wd});
  d["depth"] = cam && c.camera.calculate_depth;
  d["min_range_m"] = static_cast<double>(r.min_range);
  d["max_range_m"] = static_cast<double>(r.max_range);
  d["value_scale_m"] = r.normalize_range ? static_cast<double>(r.max_range) : 1.0;
  return d;
}

/// Every robot's mount of range image k (drawn at its environment's last reset): position in the
/// body frame and the body -> sensor rotation (xyzw), as (num_robots, 3) and (num_robots, 4).
nb::tuple sensor_mounts(const ks::Simulator& sim, int k) {
  check_image_index(sim, k);
  const ks::World& w = rigid_or_raise(sim, "sensor_mounts");
  const int si = world_ray_sensor(w, k), rpe = sim.robots_per_env();
  const std::size_t n = static_cast<std::size_t>(sim.num_robots());
  std::vector<double> p(3 * n), q(4 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const kestrel::sensors::Mount& m = w.sensor_mount(static_cast<int>(i) / rpe, si, static_cast<int>(i) % rpe);
    for (int a = 0; a < 3; ++a) p[3 * i + a] = static_cast<double>(m.position_b[a]);
    q[4 * i + 0] = static_cast<double>(m.orientation_bs.x());
    q[4 * i + 1] = static_cast<double>(m.orientation_bs.y());
    q[4 * i + 2] = static_cast<double>(m.orientation_bs.z());
    q[4 * i + 3] = static_cast<double>(m.orientation_bs.w());
  }
  return nb::make_tuple(owned_array(std::move(p), {n, 3}), owned_array(std::move(q), {n, 4}));
}

/// Environment env's obstacles in use: shape type (0 sphere, 1 box, 2 capsule, 3 cylinder,
/// 4 convex hull; sim/config.hpp ShapeType), sizes, pose, semantic id, asset kind and class, and
/// each convex hull's body-frame vertices.
nb::dict obstacle_arrays(const ks::Simulator& sim, int env) {
  const ks::World& w = rigid_or_raise(sim, "obstacles");
  if (env < 0 || env >= sim.num_envs())
    throw nb::value_error(("env: expected an env index in [0, " + std::to_string(sim.num_envs()) + "), got " + std::to_string(env)).c_str());
  const ks::WorldModel& m = w.model();
  const ks::WorldData& d = w.data();
  const std::size_t n = m.obstacle_capacity > 0 ? static_cast<std::size_t>(d.num_obstacles[static_cast<std::size_t>(env)]) : 0;
  const ks::Obstacle* o = n > 0 ? d.env_obstacles(env, m.obstacle_capacity) : nullptr;
  std::vector<std::int32_t> type(n), semantic(n), kind(n), cls(n);
  std::vector<double> radius(n), half_length(n), half_extents(3 * n), pos(3 * n), quat(4 * n);
  nb::list hulls;
  for (std::size_t i = 0; i < n; ++i) {
    const ks::Shape& s = o[i].shape;
    type[i] = static_cast<std::int32_t>(s.type);
    semantic[i] = o[i].semantic_id;
    kind[i] = static_cast<std::int32_t>(o[i].kind);
    cls[i] = o[i].class_index;
    radius[i] = static_cast<double>(s.radius_m);
    half_length[i] = static_cast<double>(s.half_length_m);
    for (int k = 0; k < 3; ++k) {
      half_extents[3 * i + k] = static_cast<double>(s.half_extents_m[k]);
      pos[3 * i + k] = static_cast<double>(s.position_w[k]);
    }
    for (int k = 0; k < 4; ++k) quat[4 * i + k] = static_cast<double>(s.orientation_wb.coeffs()[k]);  // Eigen's coeffs: x y z w
    std::vector<double> v(3 * static_cast<std::size_t>(s.type == ks::ShapeType::convex_hull ? s.num_vertices : 0));
    for (std::size_t k = 0; k < v.size() / 3; ++k)
      for (int c = 0; c < 3; ++c) v[3 * k + c] = static_cast<double>(s.vertices[k][c]);
    const std::size_t nv = v.size() / 3;
    hulls.append(owned_array(std::move(v), {nv, 3}));
  }
  nb::dict out;
  out["type"] = owned_array(std::move(type), {n});
  out["radius_m"] = owned_array(std::move(radius), {n});
  out["half_length_m"] = owned_array(std::move(half_length), {n});
  out["half_extents_m"] = owned_array(std::move(half_extents), {n, 3});
  out["position_w"] = owned_array(std::move(pos), {n, 3});
  out["orientation_xyzw"] = owned_array(std::move(quat), {n, 4});
  out["semantic_id"] = owned_array(std::move(semantic), {n});
  out["asset_kind"] = owned_array(std::move(kind), {n});
  out["asset_class"] = owned_array(std::move(cls), {n});
  out["hull_vertices_b"] = hulls;
  return out;
}

/// The robot's drawable geometry from the config and the compiled model: collision shape, rotor
/// hubs and axes (body frame), spin directions, thrust limits; the terrain's height field; the
/// body-frame offsets of the height points.
nb::dict scene_info(const ks::Simulator& sim) {
  const ks::WorldConfig& c = sim.config();
  nb::dict out;
  out["robot_name"] = c.robot.name;
  out["robot_kind"] = c.robot.kind == kestrel::robots::RobotKind::articulated      ? "articulated"
                      : c.robot.kind == kestrel::robots::RobotKind::ground_vehicle ? "ground_vehicle"
                                                                                   : "multirotor";
  out["robot_model_file"] = c.robot.model_file;
  nb::dict shape;
  shape["type"] = static_cast<int>(c.robot.shape.type);
  shape["radius_m"] = static_cast<double>(c.robot.shape.radius_m);
  shape["half_length_m"] = static_cast<double>(c.robot.shape.half_length_m);
  shape["half_extents_m"] = nb::make_tuple(static_cast<double>(c.robot.shape.half_extents_m.x()),
                                           static_cast<double>(c.robot.shape.half_extents_m.y()),
                                           static_cast<double>(c.robot.shape.half_extents_m.z()));
  out["robot_shape"] = shape;
  // Rotor geometry as compile_multirotor takes it: the URDF's rotors over the airframe preset's.
  std::vector<double> rpos, raxis, rdir;
  if (c.robot.kind == kestrel::robots::RobotKind::multirotor) {
    const kestrel::allocation::AirframeSpec& spec = kestrel::allocation::airframe_spec(c.robot.airframe);
    const bool urdf = !c.robot.rotors.empty();
    const int nr = urdf ? static_cast<int>(c.robot.rotors.size())
                        : (spec.source == kestrel::allocation::AirframeSource::rotor_geometry ? spec.num_rotors : 0);
    for (int k = 0; k < nr; ++k) {
      const kestrel::allocation::RotorSpec& r = urdf ? c.robot.rotors[static_cast<std::size_t>(k)] : spec.rotors[k];
      for (int j = 0; j < 3; ++j) {
        rpos.push_back(static_cast<double>(r.position_b_m[j]));
        raxis.push_back(static_cast<double>(r.axis_b[j]));
      }
      rdir.push_back(urdf ? c.robot.rotor_directions[static_cast<std::size_t>(k)] : spec.direction[k]);
    }
  }
  const std::size_t nr = rdir.size();
  out["rotor_position_b_m"] = owned_array(std::move(rpos), {nr, 3});
  out["rotor_axis_b"] = owned_array(std::move(raxis), {nr, 3});
  out["rotor_direction"] = owned_array(std::move(rdir), {nr});
  const ks::World* w = ks::rigid_world(sim);
  out["terrain"] = "plane";
  // The World's terrain; backends without a World (articulated robots) build theirs from the same
  // config and seed, so a second build here gives the same heights.
  std::unique_ptr<ks::Terrain> own;
  const ks::Terrain* tp = w != nullptr && w->model().terrain ? w->model().terrain.get() : nullptr;
  if (tp == nullptr && w == nullptr && sim.backend() == ks::Backend::rigid && c.env.terrain.type == ks::TerrainType::heightfield) {
    std::string err;
    if (ks::Terrain::build(c.env.terrain, c.seed, own, err)) tp = own.get();
  }
  if (tp != nullptr) {
    const ks::Terrain& t = *tp;
    out["terrain"] = t.type() == ks::TerrainType::heightfield ? "heightfield" : t.type() == ks::TerrainType::trimesh ? "trimesh" : "plane";
    if (t.type() == ks::TerrainType::heightfield) {
      std::vector<double> h(t.heights().begin(), t.heights().end());
      out["heights_m"] = owned_array(std::move(h), {static_cast<std::size_t>(t.ny()), static_cast<std::size_t>(t.nx())});
      out["height_spacing_m"] = static_cast<double>(t.spacing_m());
      out["height_corner_w"] = nb::make_tuple(static_cast<double>(t.corner_w().x()), static_cast<double>(t.corner_w().y()),
                                              static_cast<double>(t.corner_w().z()));
    }
  }
  // measured_heights' points, x-major over env.terrain.measured_points_x_m x _y_m (as every backend lays them).
  std::vector<double> hx, hy;
  if (sim.num_height_points() > 0)
    for (real x : c.env.terrain.measured_points_x_m)
      for (real y : c.env.terrain.measured_points_y_m) {
        hx.push_back(static_cast<double>(x));
        hy.push_back(static_cast<double>(y));
      }
  const std::size_t nh = hx.size();
  out["height_points_x_b"] = owned_array(std::move(hx), {nh});
  out["height_points_y_b"] = owned_array(std::move(hy), {nh});
  nb::list links;
  for (const std::string& l : sim.robot_layout().link_names) links.append(l);
  out["link_names"] = links;
  return out;
}

/// Every robot's motor thrusts after the last physics step (N; num_robots x rotors) and its
/// latched fault bits (kernel/status.hpp Fault; multirotor_faults over controller, allocator and
/// motors). Rigid multirotors; other robots have no rotors (0 columns, zero faults).
nb::tuple motor_arrays(const ks::Simulator& sim) {
  const ks::World& w = rigid_or_raise(sim, "motor_thrusts");
  const ks::WorldData& d = w.data();
  const std::size_t n = static_cast<std::size_t>(sim.num_robots());
  const bool mr = sim.config().robot.kind == kestrel::robots::RobotKind::multirotor;
  const std::size_t nm = mr && n > 0 ? static_cast<std::size_t>(std::max(0, d.mr_state[0].motors.num_motors)) : 0;
  std::vector<double> thrust(n * nm);
  std::vector<std::uint32_t> faults(n, 0);
  for (std::size_t i = 0; i < n && mr; ++i) {
    for (std::size_t k = 0; k < nm; ++k) thrust[i * nm + k] = static_cast<double>(d.mr_state[i].motors.thrust_N[k]);
    faults[i] = kestrel::robots::multirotor_faults(d.mr_state[i]);
  }
  return nb::make_tuple(owned_array(std::move(thrust), {n, nm}), owned_array(std::move(faults), {n}));
}

/// `kestrel run`'s joint targets for articulated robots (sim/src/runtime/run_scripted.cpp): one
/// stream per robot, uniform in [-1, 1], redrawn every 25 env-steps; the same draws, so a run
/// driven from Python reproduces the C++ run's state hash.
struct ScriptedJointTargets {
  std::vector<kestrel::RngStream> rng;
  std::size_t robots = 0, dofs = 0;
  std::vector<real> actions;
  long long step = 0;
};

}  // namespace

void bind_policy(nb::module_& m);  // policy_py.cpp
void bind_dynamics(nb::module_& m);  // dynamics_py.cpp
void bind_robot_model(nb::module_& m);  // robot_model_py.cpp

NB_MODULE(_core, m) {
  m.doc() = "Kestrel simulation harness (sim/) from Python: scenarios, registries, tasks, the Simulator interface.";
  m.attr("real_dtype") = sizeof(real) == 4 ? "float32" : "float64";
  bind_policy(m);
  bind_dynamics(m);
  bind_robot_model(m);

  m.def(
      "registries",
      []() {
        ks::Registries& r = ks::registries();
        nb::dict d;
        d["sims"] = registry_list(r.sims);
        d["envs"] = registry_list(r.envs);
        d["robots"] = registry_list(r.robots);
        d["controllers"] = registry_list(r.controllers);
        d["sensors"] = registry_list(r.sensors);
        d["tasks"] = registry_list(r.tasks);
        d["simulators"] = registry_list(r.simulators);
        return d;
      },
      "Every registry as {kind: [(name, description), ...]} (kinds: sims, envs, robots, controllers, sensors, tasks, simulators).");
  m.def("rl_task_ids", &ks::rl_task_ids, "Every task id make_task accepts (sorted).");
  m.def("default_scenario_yaml", []() { return std::string(ks::default_scenario_yaml()); });
  m.def("box2d_hooks_active", &box2d_hooks_active,
        "True if sim/src/backends/planar.cpp's b2Alloc_Default/b2Free_Default interpose on libbox2d's inside this module.");

  nb::class_<KConfig>(m, "Config", "A parsed scenario (sim/config.hpp WorldConfig); a few fields can be changed before make_task.")
      .def_prop_rw(
          "seed", [](const KConfig& c) { return c.cfg.seed; },
          [](KConfig& c, std::int64_t v) {
            if (v < 0) throw nb::value_error(("seed: expected an integer >= 0, got " + std::to_string(v)).c_str());
            c.cfg.seed = static_cast<std::uint64_t>(v);
          })
      .def_prop_rw(
          "num_envs", [](const KConfig& c) { return c.cfg.env.num_envs; },
          [](KConfig& c, int v) {
            if (v < 1) throw nb::value_error(("num_envs: expected an integer >= 1, got " + std::to_string(v)).c_str());
            c.cfg.env.num_envs = v;
          })
      .def_prop_rw(
          "first_env_index", [](const KConfig& c) { return c.cfg.env.first_env_index; },
          [](KConfig& c, int v) {
            if (v < 0 || v >= ks::kMaxNumEnvs)
              throw nb::value_error(("first_env_index: expected an integer in [0, " + std::to_string(ks::kMaxNumEnvs - 1) + "], got " +
                                     std::to_string(v)).c_str());
            c.cfg.env.first_env_index = v;
          },
          "env.first_env_index: global index of environment 0 when this world is a slice of a larger run.")
      .def_prop_rw(
          "total_num_envs", [](const KConfig& c) { return c.cfg.env.total_num_envs; },
          [](KConfig& c, int v) {
            if (v < 0 || v > ks::kMaxNumEnvs)
              throw nb::value_error(("total_num_envs: expected 0 or an integer in [1, " + std::to_string(ks::kMaxNumEnvs) + "], got " +
                                     std::to_string(v)).c_str());
            c.cfg.env.total_num_envs = v;
          },
          "env.total_num_envs: environments of the whole run this world is a slice of (0: num_envs).")
      .def_prop_rw(
          "num_threads", [](const KConfig& c) { return c.cfg.num_threads; },
          [](KConfig& c, int v) {
            if (v < 1) throw nb::value_error(("threads: expected an integer >= 1, got " + std::to_string(v)).c_str());
            c.cfg.num_threads = v;
          })
      .def_prop_rw(
          "episode_len_env_steps", [](const KConfig& c) { return c.cfg.task.episode_len_env_steps; },
          [](KConfig& c, int v) {
            if (v < 1) throw nb::value_error(("episode_len_env_steps: expected an integer >= 1, got " + std::to_string(v)).c_str());
            c.cfg.task.episode_len_env_steps = v;
          })
      .def_prop_rw(
          "setpoint_speed_m_s", [](const KConfig& c) { return static_cast<double>(c.cfg.task.setpoint_speed_m_s); },
          [](KConfig& c, double v) {
            // Teleoperation (kestrel.viewer.Teleop) sets 0: a moving setpoint would overwrite its commands.
            if (!(v >= 0) || !std::isfinite(v))
              throw nb::value_error(("setpoint_speed_m_s: expected a finite number >= 0 (m/s; 0: no moving setpoint), got " +
                                     std::to_string(v)).c_str());
            c.cfg.task.setpoint_speed_m_s = static_cast<real>(v);
          })
      .def_prop_ro("task", [](const KConfig& c) { return c.cfg.task.name; })
      .def_prop_ro("controller", [](const KConfig& c) { return c.cfg.controller.name; })
      .def_prop_ro("env", [](const KConfig& c) { return c.cfg.env.name; })
      .def_prop_ro("robot", [](const KConfig& c) { return c.cfg.robot.name; })
      .def_prop_ro("sim", [](const KConfig& c) { return c.cfg.sim.name; })
      .def_prop_ro("simulator", [](const KConfig& c) { return c.cfg.simulator.backend; })
      .def_prop_ro("success_radius_m", [](const KConfig& c) { return static_cast<double>(c.cfg.task.success_radius_m); })
      .def_prop_ro("dt_s", [](const KConfig& c) { return static_cast<double>(c.cfg.sim.dt_s); })
      .def_ro("source", &KConfig::source)
      .def("__repr__", [](const KConfig& c) {
        return "kestrel.Config(task=" + c.cfg.task.name + ", env=" + c.cfg.env.name + ", robot=" + c.cfg.robot.name +
               ", controller=" + c.cfg.controller.name + ", num_envs=" + std::to_string(c.cfg.env.num_envs) +
               ", seed=" + std::to_string(c.cfg.seed) + ", threads=" + std::to_string(c.cfg.num_threads) + ")";
      });

  m.def("load_scenario_string", &load_string, "text"_a, "name"_a = "<string>", "base_dir"_a = "",
        "Parses a scenario from YAML text (JSON is YAML too); files it names are relative to base_dir (default: the "
        "current directory). ValueError names the field and the allowed values.");
  m.def(
      "register_preset",
      [](const std::string& kind, const std::string& name, const std::string& section, const std::string& description) {
        std::string err;
        if (!ks::register_preset(kind, name, section, description, err)) throw nb::value_error(err.c_str());
      },
      "kind"_a, "name"_a, "section"_a, "description"_a = "",
      "Registers a preset (sim, env, robot, controller, sensor, task, simulator) from a scenario section (YAML/JSON text).");
  m.def("load_scenario_file", &load_file, "path"_a, "Parses a scenario file (paths inside are relative to it).");

  nb::class_<KTask>(m, "Task",
                     "An RL task (sim/task.hpp): step(actions) with auto-reset inside; arrays view the task's buffers.")
      .def(nb::new_(&make_task), "config"_a, "backend"_a = "",
           "Builds the task config.task names on `backend` ('rigid', 'planar', or '' = KESTREL_SIMULATOR / the scenario's).")
      .def_prop_ro("name", [](KTask& p) { return std::string(p.t().name()); })
      .def_prop_ro("backend", [](KTask& p) { return std::string(p.t().backend_name()); })
      .def_prop_ro("num_envs", [](KTask& p) { return p.t().num_envs(); })
      .def_prop_ro("obs_dim", [](KTask& p) { return p.t().obs_dim(); })
      .def_prop_ro("action_dim", [](KTask& p) { return p.t().action_dim(); })
      .def_prop_ro("num_threads", [](KTask& p) { return p.t().num_threads(); })
      .def_prop_ro("seed", [](KTask& p) { return p.cfg.seed; })
      .def_prop_ro("controller",
                   [](KTask& p) {
                     // An articulated robot is driven by its joint PD, not the scenario's controller.
                     return p.t().simulator().config().robot.kind == kestrel::robots::RobotKind::articulated
                                ? std::string(p.t().simulator().controller_name())
                                : p.cfg.controller.name;
                   })
      .def_prop_ro("success_radius_m", [](KTask& p) { return static_cast<double>(p.cfg.task.success_radius_m); })
      .def_prop_ro(
          "action_bounds",
          [](KTask& p) -> nb::object {
            std::vector<float> lo(p.ad()), hi(p.ad());
            if (!p.t().action_bounds(lo.data(), hi.data())) return nb::none();
            return nb::make_tuple(lo, hi);
          },
          "(low, high) lists of action_dim floats where the task clamps each action component to its own range "
          "(so101_pick_place: the joint ranges), else None.")
      .def_prop_ro("episode_len_env_steps", [](KTask& p) { return p.cfg.task.episode_len_env_steps; })
      .def_prop_ro("state_hash", [](KTask& p) { return p.t().state_hash(); })
      .def_prop_ro(
          "simulator",
          [](KTask& p) {
            // A non-owning Simulator over the task's own; keep_alive below holds the task while it lives.
            return new KSimulator(nullptr, &p.t().simulator());
          },
          nb::rv_policy::take_ownership, nb::keep_alive<0, 1>(),
          "The Simulator the task steps (its views, world_data(), obstacles(), ...), kept alive with the task.\n"
          "Read it between task steps; stepping or resetting it yourself changes the task's episodes.")
      .def_prop_ro(
          "summary", [](KTask& p) { return summary_dict(p.t().simulator().summary()); },
          "The simulator's run summary, as `kestrel run` prints it (sim/summary.hpp): env_steps, crashes, resets, "
          "timeouts, episodes_done, successes, mean_tracking_error_m, final_mean_distance_m, fault_bits, reset_errors, ...")
      .def_prop_ro(
          "infos",
          [](KTask& p) {
            nb::dict d = infos_dict(p.t().infos());
            // Reward terms (locomotion_task): rew_<term>, summed over the finished episodes.
            for (int k = 0; k < p.t().num_reward_terms(); ++k)
              d[("rew_" + std::string(p.t().reward_term_name(k))).c_str()] = p.t().reward_term_sum(k);
            return d;
          },
          "Episode statistics since the task was built (locomotion_task also rew_<term>: each reward term summed "
          "over the finished episodes, scaled, as legged_gym's episode_sums).")
      .def_prop_ro(
          "observations",
          [](nb::pointer_and_handle<KTask> s) { return view2<float>(s.p->t().observations(), s.p->n(), s.p->od(), s.h); },
          "(num_envs, obs_dim) float32 view; after step(), an ended env's row is its next episode's first observation.")
      .def_prop_ro(
          "final_observations",
          [](nb::pointer_and_handle<KTask> s) {
            return view2<float>(s.p->t().final_observations(), s.p->n(), s.p->od(), s.h);
          },
          "(num_envs, obs_dim) float32 view: rows of envs that ended in the last step hold their final observation.")
      .def_prop_ro(
          "rewards",
          [](nb::pointer_and_handle<KTask> s) {
            return Array1<float>(const_cast<float*>(s.p->t().rewards()), {s.p->n()}, s.h);
          },
          "(num_envs,) float32 view of the last step's rewards.")
      .def_prop_ro(
          "terminations",
          [](nb::pointer_and_handle<KTask> s) {
            return Array1<bool>(reinterpret_cast<bool*>(const_cast<std::uint8_t*>(s.p->t().terminations())), {s.p->n()}, s.h);
          },
          "(num_envs,) bool view: the last step ended the episode (crash, success where the task ends on it).")
      .def_prop_ro(
          "truncations",
          [](nb::pointer_and_handle<KTask> s) {
            return Array1<bool>(reinterpret_cast<bool*>(const_cast<std::uint8_t*>(s.p->t().truncations())), {s.p->n()}, s.h);
          },
          "(num_envs,) bool view: the last step reached the episode length.")
      .def_prop_ro(
          "base_lin_vel_b",
          [](nb::pointer_and_handle<KTask> s) {
            return view2<real>(s.p->t().simulator().base_lin_vel_b(), s.p->n(), 3, s.h);
          },
          "(num_envs, 3) view of the task's robots' base linear velocity in the body frame (m/s), noise-free.")
      .def_prop_ro(
          "base_ang_vel_b",
          [](nb::pointer_and_handle<KTask> s) {
            return view2<real>(s.p->t().simulator().base_ang_vel_b(), s.p->n(), 3, s.h);
          },
          "(num_envs, 3) view of the task's robots' base angular velocity in the body frame (rad/s), noise-free.")
      .def(
          "reset", [](KTask& p) {
            nb::gil_scoped_release release;
            p.t().reset();
          },
          "Resets every environment (observations: first observations; rewards and flags zero).")
      .def(
          "reset_idx",
          [](KTask& p, const std::vector<int>& ids) {
            for (int id : ids)
              if (id < 0 || static_cast<std::size_t>(id) >= p.n())
                throw nb::value_error(("env_ids: expected ids in [0, " + std::to_string(p.n()) + "), got " + std::to_string(id)).c_str());
            nb::gil_scoped_release release;
            p.t().reset_idx(ids.data(), static_cast<int>(ids.size()));
          },
          "env_ids"_a)
      .def(
          "step",
          [](KTask& p, nb::handle actions) {
            const float* a = checked_actions<float>(actions, p.n(), p.ad(), "actions");
            bool ended = false;
            {
              nb::gil_scoped_release release;
              p.t().step(a);
              const std::uint8_t* te = p.t().terminations();
              const std::uint8_t* tr = p.t().truncations();
              for (std::size_t i = 0; i < p.n(); ++i) ended = ended || te[i] != 0 || tr[i] != 0;
            }
            return ended;
          },
          "actions"_a,
          "One task step; actions: C-contiguous float32 (num_envs, action_dim), read in place. The GIL is released.\n"
          "Returns True if any environment's episode ended in this step (terminated or truncated).")
      .def(
          "step_n",
          [](KTask& p, nb::handle actions, long long n) {
            if (n < 0) throw nb::value_error("n: expected an integer >= 0");
            const float* a = checked_actions<float>(actions, p.n(), p.ad(), "actions");
            nb::gil_scoped_release release;
            for (long long k = 0; k < n; ++k) p.t().step(a);
          },
          "actions"_a, "n"_a, "n steps in C++ with the same actions (the C++ side of bench/python/overhead.py).")
      .def(
          "scripted_actions",
          [](KTask& p) {
            auto* buf = new float[p.n() * p.ad()]();
            nb::capsule owner(buf, [](void* q) noexcept { delete[] static_cast<float*>(q); });
            if (!p.t().scripted_actions(buf))
              throw nb::value_error(("task " + std::string(p.t().name()) + " has no scripted controller for controller " +
                                     p.cfg.controller.name)
                                        .c_str());
            return Array2<float>(buf, {p.n(), p.ad()}, owner);
          },
          "The task's built-in scripted controller's actions for the current state (what `kestrel run` drives).")
      .def(
          "render_camera",
          [](KTask& p, int env, const std::string& camera, int width, int height) {
            const ks::PickPlaceWorld* w = pick_place_env(p, env);
            ks::CameraSpec cam;
            if (camera == "front") cam = ks::front_camera(width, height);
            else if (camera == "wrist") cam = ks::wrist_camera(*w, width, height);
            else throw nb::value_error(("camera: expected \"front\" or \"wrist\" (got \"" + camera + "\")").c_str());
            if (width < 1 || height < 1 || width > 2048 || height > 2048)
              throw nb::value_error("width, height: expected 1..2048 pixels");
            const std::size_t px = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
            auto* rgb = new std::uint8_t[3 * px]();
            auto* depth = new float[px]();
            auto* seg = new std::uint8_t[px]();
            nb::capsule o_rgb(rgb, [](void* q) noexcept { delete[] static_cast<std::uint8_t*>(q); });
            nb::capsule o_depth(depth, [](void* q) noexcept { delete[] static_cast<float*>(q); });
            nb::capsule o_seg(seg, [](void* q) noexcept { delete[] static_cast<std::uint8_t*>(q); });
            kestrel::Status st;
            {
              nb::gil_scoped_release release;
              st = ks::render_camera(*w, cam, rgb, depth, seg);
            }
            if (st != kestrel::Status::ok) throw nb::value_error(("render_camera: " + std::string(kestrel::to_string(st))).c_str());
            const std::size_t h = static_cast<std::size_t>(height), wd = static_cast<std::size_t>(width);
            return nb::make_tuple(nb::ndarray<nb::numpy, std::uint8_t, nb::ndim<3>>(rgb, {h, wd, 3}, o_rgb),
                                  nb::ndarray<nb::numpy, float, nb::ndim<2>>(depth, {h, wd}, o_depth),
                                  nb::ndarray<nb::numpy, std::uint8_t, nb::ndim<2>>(seg, {h, wd}, o_seg));
          },
          "env"_a, "camera"_a = "front", "width"_a = 640, "height"_a = 480,
          "so101_pick_place only: environment env's image from the front or wrist camera "
          "(sim/pick_place_camera.hpp): (rgb uint8 (h, w, 3), depth float32 (h, w) metres along the optical axis, "
          "+inf where nothing is hit, segmentation uint8 (h, w): 0 table, 1 robot, 2 cube, 3 box, 255 nothing).")
      .def(
          "pick_place_state",
          [](KTask& p, int env) {
            const ks::PickPlaceWorld* w = pick_place_env(p, env);
            const ks::PickPlaceState& st = w->state();
            auto v3 = [](const kestrel::Vec3& v) { return std::vector<double>{v[0], v[1], v[2]}; };
            nb::dict d;
            d["tcp_pos_w"] = v3(st.tcp_pos_w);
            std::vector<double> R;
            for (int r = 0; r < 3; ++r)
              for (int c = 0; c < 3; ++c) R.push_back(st.tcp_R_w(r, c));
            d["tcp_R_w"] = R;
            d["cube_pos_w"] = v3(st.cube_pos_w);
            d["cube_quat_xyzw"] = std::vector<double>{st.cube_quat_xyzw[0], st.cube_quat_xyzw[1], st.cube_quat_xyzw[2], st.cube_quat_xyzw[3]};
            d["box_pos_w"] = v3(st.box_pos_w);
            d["grip_force_N"] = static_cast<double>(w->grip_force_N());
            d["contacts"] = w->contacts();  // the last physics step's contact points
            d["cube_in_box"] = w->cube_in_box();
            d["joint_pos"] = std::vector<double>(w->joint_pos(), w->joint_pos() + ks::PickPlaceWorld::kJoints);
            d["joint_targets"] = std::vector<double>(w->joint_targets(), w->joint_targets() + ks::PickPlaceWorld::kJoints);
            // Every collision shape at the current state, for viewers: entity, type, size, centre and
            // rotation (shape -> world, row-major) in the world.
            ks::PickPlaceShape shapes[64];
            const int n = std::min(64, w->scene_shapes(shapes, 64));
            nb::list out;
            const char* entity[] = {"table", "robot", "cube", "box"};
            const char* type[] = {"sphere", "capsule", "box"};
            for (int i = 0; i < n; ++i) {
              const ks::PickPlaceShape& sh = shapes[i];
              const kestrel::Mat3 Rw = sh.X_body.E.transpose() * sh.shape.R_b;
              const kestrel::Vec3 cw = sh.X_body.r + sh.X_body.E.transpose() * sh.shape.p_b;
              nb::dict e;
              e["entity"] = entity[static_cast<int>(sh.entity)];
              e["index"] = sh.index;
              e["type"] = type[static_cast<int>(sh.shape.type)];
              e["size"] = v3(sh.shape.size);
              e["pos_w"] = v3(cw);
              std::vector<double> Rs;
              for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) Rs.push_back(Rw(r, c));
              e["R_w"] = Rs;
              out.append(e);
            }
            d["shapes"] = out;
            return d;
          },
          "env"_a,
          "so101_pick_place only: environment env's scene now: tool centre point, cube, box, grip force (N), "
          "cube_in_box, joint positions and targets, and every collision shape in the world (for viewers).")
      .def(
          "pick_place_poses",
          [](KTask& p) {
            (void)pick_place_env(p, 0);
            const std::size_t n = p.n();
            nb::dict d;
            // Copies (float64, C order) of every environment's state: each call allocates new arrays.
            auto array = [&](const char* key, std::size_t cols, auto fill) {
              auto* buf = new double[n * cols]();
              nb::capsule owner(buf, [](void* q) noexcept { delete[] static_cast<double*>(q); });
              for (std::size_t e = 0; e < n; ++e) fill(*ks::pick_place_world(p.t(), static_cast<int>(e)), buf + e * cols);
              d[key] = Array2<double>(buf, {n, cols}, owner);
            };
            array("cube_pos_w", 3, [](const ks::PickPlaceWorld& w, double* o) { for (int k = 0; k < 3; ++k) o[k] = w.state().cube_pos_w[k]; });
            array("cube_quat_xyzw", 4, [](const ks::PickPlaceWorld& w, double* o) { for (int k = 0; k < 4; ++k) o[k] = w.state().cube_quat_xyzw[k]; });
            array("box_pos_w", 3, [](const ks::PickPlaceWorld& w, double* o) { for (int k = 0; k < 3; ++k) o[k] = w.state().box_pos_w[k]; });
            array("tcp_pos_w", 3, [](const ks::PickPlaceWorld& w, double* o) { for (int k = 0; k < 3; ++k) o[k] = w.state().tcp_pos_w[k]; });
            array("tcp_quat_xyzw", 4, [](const ks::PickPlaceWorld& w, double* o) {
              kestrel::Vec4 q = kestrel::to_xyzw(kestrel::quat_from_rotation_matrix(w.state().tcp_R_w));
              if (q[3] < 0) q = -q;
              for (int k = 0; k < 4; ++k) o[k] = q[k];
            });
            const int J = ks::PickPlaceWorld::kJoints;
            array("joint_pos", J, [J](const ks::PickPlaceWorld& w, double* o) { for (int k = 0; k < J; ++k) o[k] = w.joint_pos()[k]; });
            array("joint_vel", J, [J](const ks::PickPlaceWorld& w, double* o) { for (int k = 0; k < J; ++k) o[k] = w.joint_vel()[k]; });
            array("joint_targets", J, [J](const ks::PickPlaceWorld& w, double* o) { for (int k = 0; k < J; ++k) o[k] = w.joint_targets()[k]; });
            array("grip_force_N", 1, [](const ks::PickPlaceWorld& w, double* o) { o[0] = w.grip_force_N(); });
            auto* in_box = new bool[n]();
            nb::capsule o_in(in_box, [](void* q) noexcept { delete[] static_cast<bool*>(q); });
            for (std::size_t e = 0; e < n; ++e) in_box[e] = ks::pick_place_world(p.t(), static_cast<int>(e))->cube_in_box();
            d["cube_in_box"] = Array1<bool>(in_box, {n}, o_in);
            return d;
          },
          "so101_pick_place only: every environment's scene state now as new float64 arrays (copies, not views: "
          "read them again after a step): cube_pos_w (n, 3), cube_quat_xyzw (n, 4), box_pos_w (n, 3; the centre of "
          "the box floor's bottom face), tcp_pos_w (n, 3), tcp_quat_xyzw (n, 4, w >= 0), joint_pos, joint_vel, "
          "joint_targets (n, 6), grip_force_N (n, 1), and cube_in_box (n,) bool (LeIsaac's term, the C++ one).")
      .def(
          "set_object_pose",
          [](KTask& p, int env, const std::string& object, const std::vector<double>& pos, const std::vector<double>& quat) {
            (void)pick_place_env(p, env);
            ks::PickPlaceObject obj;
            if (object == "cube") obj = ks::PickPlaceObject::cube;
            else if (object == "box") obj = ks::PickPlaceObject::box;
            else throw nb::value_error(("object: expected \"cube\" or \"box\" (got \"" + object + "\")").c_str());
            if (pos.size() != 3) throw nb::value_error(("pos: expected 3 numbers (x, y, z in m), got " + std::to_string(pos.size())).c_str());
            if (quat.size() != 4)
              throw nb::value_error(("quat: expected 4 numbers (x, y, z, w), got " + std::to_string(quat.size())).c_str());
            std::string err;
            if (!ks::pick_place_set_object_pose(p.t(), env, obj, kestrel::Vec3(static_cast<real>(pos[0]), static_cast<real>(pos[1]), static_cast<real>(pos[2])),
                                                kestrel::Vec4(static_cast<real>(quat[0]), static_cast<real>(quat[1]), static_cast<real>(quat[2]),
                                                              static_cast<real>(quat[3])),
                                                err))
              throw nb::value_error(("set_object_pose: " + err).c_str());
          },
          "env"_a, "object"_a, "pos"_a, "quat"_a = std::vector<double>{0, 0, 0, 1},
          "so101_pick_place only, between steps: puts environment env's \"cube\" at pos (its centre, m) with "
          "orientation quat (x, y, z, w; normalised), at rest, or the \"box\" at pos (its floor's bottom-face "
          "centre; quat not read), as an event term does after a reset. The observation row, the views and the "
          "scripted controller follow; the next reset draws the objects again.")
      .def(
          "pick_place_config",
          [](KTask& p) {
            const ks::PickPlaceConfig& c = pick_place_env(p, 0)->config();
            auto v3 = [](const kestrel::Vec3& v) { return std::vector<double>{v[0], v[1], v[2]}; };
            nb::dict d;
            d["robot_file"] = c.robot_file;
            d["dt_s"] = static_cast<double>(c.dt_s);
            d["decimation"] = c.decimation;
            d["cube_half_m"] = static_cast<double>(c.cube_half_m);
            d["cube_mass_kg"] = static_cast<double>(c.cube_mass_kg);
            d["cube_friction"] = static_cast<double>(c.cube_friction);
            d["cube_pos_w"] = v3(c.cube_pos_w);
            d["box_pos_w"] = v3(c.box_pos_w);
            d["box_inner_half_m"] = static_cast<double>(c.box_inner_half_m);
            d["box_wall_m"] = static_cast<double>(c.box_wall_m);
            d["box_height_m"] = static_cast<double>(c.box_height_m);
            d["box_friction"] = static_cast<double>(c.box_friction);
            d["table_friction"] = static_cast<double>(c.table_friction);
            d["randomize_xy_m"] = static_cast<double>(c.randomize_xy_m);
            d["success_xy_m"] = static_cast<double>(c.success_xy_m);
            d["success_height_m"] = static_cast<double>(c.success_height_m);
            return d;
          },
          "so101_pick_place only: the scene the worlds were built from (sim/pick_place.hpp's PickPlaceConfig; "
          "robot_file resolved): cube and box sizes, nominal positions, frictions, randomisation and success thresholds.");

  nb::class_<KSimulator>(m, "Simulator", "The Simulator interface (sim/simulator.hpp) with its views as numpy arrays.")
      .def(
          "__init__",
          [](KSimulator* self, const KConfig& c, const std::string& backend) {
            const ks::Backend b = pick_backend(c.cfg, backend);
            std::string err;
            std::unique_ptr<ks::Simulator> s;
            {
              nb::gil_scoped_release release;
              s = ks::make_simulator(c.cfg, b, err);
            }
            if (!s) throw nb::value_error((c.source + ": " + err).c_str());
            ks::Simulator* raw = s.get();
            new (self) KSimulator(std::move(s), raw);
          },
          "config"_a, "backend"_a = "")
      .def_prop_ro("backend", [](KSimulator& s) { return std::string(s.sim->backend_name()); })
      .def_prop_ro("controller", [](KSimulator& s) { return std::string(s.sim->controller_name()); })
      .def_prop_ro("num_envs", [](KSimulator& s) { return s.sim->num_envs(); })
      .def_prop_ro("num_robots", [](KSimulator& s) { return s.sim->num_robots(); })
      .def_prop_ro("robots_per_env", [](KSimulator& s) { return s.sim->robots_per_env(); })
      .def_prop_ro("action_dim", [](KSimulator& s) { return s.sim->action_dim(); })
      .def_prop_ro("num_threads", [](KSimulator& s) { return s.sim->num_threads(); })
      .def_prop_ro("decimation", [](KSimulator& s) { return s.sim->decimation(); })
      .def_prop_ro("dt_s", [](KSimulator& s) { return static_cast<double>(s.sim->dt_s()); })
      .def_prop_ro("lidar_beams", [](KSimulator& s) { return s.sim->lidar_beams(); })
      .def_prop_ro("state_hash", [](KSimulator& s) { return s.sim->state_hash(); })
      .def_prop_ro(
          "summary", [](KSimulator& s) { return summary_dict(s.sim->summary()); },
          "The run summary, as `kestrel run` prints it (sim/summary.hpp WorldSummary) as a dict.")
      .def_prop_ro("step_heap_fallbacks", [](KSimulator& s) { return s.sim->step_heap_fallbacks(); })
      .def(
          "step",
          [](KSimulator& s, nb::handle actions) {
            const real* a = nullptr;
            if (!actions.is_none())
              a = checked_actions<real>(actions, s.robots(), static_cast<std::size_t>(s.sim->action_dim()), "actions");
            nb::gil_scoped_release release;
            s.sim->step(a);
          },
          "actions"_a = nb::none(), "decimation physics steps then post_physics_step; actions (num_robots, action_dim) or None.")
      .def(
          "reset_idx",
          [](KSimulator& s, const std::vector<int>& ids) {
            for (int id : ids)
              if (id < 0 || id >= s.sim->num_envs())
                throw nb::value_error(("env_ids: expected ids in [0, " + std::to_string(s.sim->num_envs()) + "), got " + std::to_string(id)).c_str());
            nb::gil_scoped_release release;
            s.sim->reset_idx(ids.data(), static_cast<int>(ids.size()));
          },
          "env_ids"_a)
      .def("push_robots", [](KSimulator& s) { s.sim->push_robots(); })
      .def(
          "set_viewer_camera",
          [](KSimulator& s, const std::array<double, 3>& position, const std::array<double, 3>& lookat) {
            const kestrel::Vec3 p(static_cast<real>(position[0]), static_cast<real>(position[1]), static_cast<real>(position[2]));
            const kestrel::Vec3 l(static_cast<real>(lookat[0]), static_cast<real>(lookat[1]), static_cast<real>(lookat[2]));
            if (!s.sim->set_viewer_camera(p, l)) throw nb::value_error(s.sim->last_error().c_str());
          },
          "position"_a, "lookat"_a,
          "LeggedGym-Ex's set_viewer_camera (m, world frame): kept, and handed to the attached viewer (attach_viewer).")
      .def(
          "draw_debug_vis", [](KSimulator& s, bool height_samples, bool contacts) { s.sim->draw_debug_vis(height_samples, contacts); },
          "height_samples"_a = true, "contacts"_a = true,
          "LeggedGym-Ex's draw_debug_vis: the attached viewer draws the height samples and / or the contacts and their forces.")
      .def(
          "attach_viewer",
          [](KSimulator& s, nb::object viewer) {
            if (viewer.is_none()) {
              s.sim->set_viewer(nullptr);
              s.viewer.reset();
              return;
            }
            for (const char* method : {"set_viewer_camera", "draw_debug_vis"})
              if (!nb::hasattr(viewer, method))
                throw nb::type_error((std::string("attach_viewer: the viewer has no ") + method + " method (kestrel.viewer.Viewer has both)").c_str());
            auto hooks = std::make_unique<PyViewerHooks>();
            hooks->viewer = viewer;
            s.sim->set_viewer(nullptr);
            s.viewer = std::move(hooks);
            s.sim->set_viewer(s.viewer.get());  // hands it the camera and debug request made so far
          },
          "viewer"_a.none(), "Attach a viewer (None detaches): it gets set_viewer_camera / draw_debug_vis requests.")
      .def_prop_ro("viewer_request",
                   [](KSimulator& s) {
                     const ks::Simulator::ViewerRequest& r = s.sim->viewer_request();
                     nb::dict d;
                     d["camera_set"] = r.camera_set;
                     d["camera_position_w"] = nb::make_tuple(r.camera_position_w[0], r.camera_position_w[1], r.camera_position_w[2]);
                     d["camera_lookat_w"] = nb::make_tuple(r.camera_lookat_w[0], r.camera_lookat_w[1], r.camera_lookat_w[2]);
                     d["debug_height_samples"] = r.debug_height_samples;
                     d["debug_contacts"] = r.debug_contacts;
                     return d;
                   })
      .def(
          "set_auto_reset", [](KSimulator& s, bool on) { s.sim->set_auto_reset(on); }, "on"_a,
          "False: step() only flags reset_buf for ended episodes; the caller reads the final state and calls reset_idx.")
      .def_prop_ro("episode_len_env_steps", [](KSimulator& s) { return s.sim->config().task.episode_len_env_steps; })
      .def("update_sensors", [](KSimulator& s) {
        nb::gil_scoped_release release;
        s.sim->update_sensors();
      })
      .def(
          "scripted_actions",
          [](KSimulator& s) {
            const std::size_t n = s.robots() * static_cast<std::size_t>(s.sim->action_dim());
            auto* buf = new real[n]();
            nb::capsule owner(buf, [](void* q) noexcept { delete[] static_cast<real*>(q); });
            ks::scripted_setpoint_actions(*s.sim, buf);
            return Array2<real>(buf, {s.robots(), static_cast<std::size_t>(s.sim->action_dim())}, owner);
          },
          "The scripted position-setpoint policy (`kestrel run`): Lee targets or pure pursuit.")
#define KESTREL_VIEW(NAME, COLS)                                                                            \
  .def_prop_ro(#NAME, [](nb::pointer_and_handle<KSimulator> s) {                                          \
    return view2<real>(s.p->sim->NAME(), s.p->robots(), static_cast<std::size_t>(COLS), s.h);              \
  })
      KESTREL_VIEW(base_pos_w, 3) KESTREL_VIEW(base_quat_xyzw, 4) KESTREL_VIEW(base_euler_xyz, 3)
      KESTREL_VIEW(base_lin_vel_b, 3) KESTREL_VIEW(base_ang_vel_b, 3) KESTREL_VIEW(contact_forces_w, 3)
      KESTREL_VIEW(applied_wrench_b, 6) KESTREL_VIEW(target_w, 3)
      // Articulated robots (robot kind articulated): legged_gym's joint and link views, zero-copy.
      KESTREL_VIEW(dof_pos, s.p->sim->num_dofs()) KESTREL_VIEW(dof_vel, s.p->sim->num_dofs())
      KESTREL_VIEW(torques, s.p->sim->num_dofs())
#undef KESTREL_VIEW
      .def_prop_ro("dr_kp_scale", [](nb::pointer_and_handle<KSimulator> s) {
        return Array1<real>(const_cast<real*>(s.p->sim->dr_kp_scale()), {s.p->robots()}, s.h);
      }, "(num_robots,) each robot's joint stiffness scale, drawn at its resets in robot.joint_kp_scale")
      .def_prop_ro("dr_kd_scale", [](nb::pointer_and_handle<KSimulator> s) {
        return Array1<real>(const_cast<real*>(s.p->sim->dr_kd_scale()), {s.p->robots()}, s.h);
      }, "(num_robots,) each robot's joint damping scale, drawn at its resets in robot.joint_kd_scale")
      .def_prop_ro("dr_friction_values", [](nb::pointer_and_handle<KSimulator> s) {
        return Array1<real>(const_cast<real*>(s.p->sim->dr_friction_values()), {s.p->robots()}, s.h);
      }, "(num_robots,) each robot's ground-contact friction coefficient, drawn at its resets in simulator.friction (-1: not randomised)")
      .def_prop_ro("dr_restitution_values", [](nb::pointer_and_handle<KSimulator> s) {
        return Array1<real>(const_cast<real*>(s.p->sim->dr_restitution_values()), {s.p->robots()}, s.h);
      }, "(num_robots,) each robot's ground-contact restitution, drawn at its resets in simulator.restitution (-1: not randomised)")
      .def_prop_ro("dr_added_base_mass", [](nb::pointer_and_handle<KSimulator> s) {
        return Array1<real>(const_cast<real*>(s.p->sim->added_mass_kg()), {s.p->robots()}, s.h);
      }, "(num_robots,) mass added to each robot's base (root body), drawn at its resets in simulator.added_mass_kg (kg)")
      .def_prop_ro("dr_base_com_bias", [](nb::pointer_and_handle<KSimulator> s) {
        return view2<real>(s.p->sim->com_bias_b_m(), s.p->robots(), 3, s.h);
      }, "(num_robots, 3) each robot's base centre-of-mass offset (body frame, m), drawn in [-simulator.com_bias_max_m, max]")
      .def_prop_ro("dr_joint_armature", [](nb::pointer_and_handle<KSimulator> s) {
        static const real kNone = 0;  // a valid pointer for the (robots, 0) view without joints
        const real* p = s.p->sim->num_dofs() > 0 ? s.p->sim->dr_joint_armature() : &kNone;
        return view2<real>(p, s.p->robots(), static_cast<std::size_t>(s.p->sim->num_dofs()), s.h);
      }, "(num_robots, num_dofs) each actuated joint's armature in effect (kg m^2), drawn in simulator.joint_armature_kg_m2 when randomised")
      .def_prop_ro("num_terrain_levels", [](KSimulator& s) { return s.sim->num_terrain_levels(); },
                   "levels (tile rows) of a tiled terrain (env.terrain.procedural curriculum / randomized); 0 otherwise")
      .def_prop_ro("terrain_levels", [](nb::pointer_and_handle<KSimulator> s) {
        return Array1<int>(const_cast<int*>(s.p->sim->terrain_levels()), {static_cast<std::size_t>(s.p->sim->num_envs())}, s.h);
      }, "(num_envs,) each environment's terrain level (tiled terrain)")
      .def_prop_ro("terrain_types", [](nb::pointer_and_handle<KSimulator> s) {
        return Array1<int>(const_cast<int*>(s.p->sim->terrain_types()), {static_cast<std::size_t>(s.p->sim->num_envs())}, s.h);
      }, "(num_envs,) each environment's terrain type (tile column, tiled terrain)")
      .def_prop_ro("env_origins_w", [](nb::pointer_and_handle<KSimulator> s) {
        return view2<real>(s.p->sim->env_origins_w(), static_cast<std::size_t>(s.p->sim->num_envs()), 3, s.h);
      }, "(num_envs, 3) where each environment's robot starts (articulated robots: grid or tile origin, m)")
      .def(
          "update_terrain_curriculum",
          [](KSimulator& s, const std::vector<int>& ids, const std::vector<bool>& up, const std::vector<bool>& down) {
            if (up.size() != ids.size() || down.size() != ids.size())
              throw nb::value_error(("update_terrain_curriculum: move_up and move_down: expected " + std::to_string(ids.size()) +
                                     " values each (one per env id)").c_str());
            std::vector<std::uint8_t> u(up.begin(), up.end()), d(down.begin(), down.end());
            if (!s.sim->update_terrain_curriculum(ids.data(), static_cast<int>(ids.size()), u.data(), d.data()))
              throw nb::value_error(s.sim->last_error().c_str());
          },
          "env_ids"_a, "move_up"_a, "move_down"_a,
          "legged_gym's terrain curriculum: levels up / down (past the top: a random level); the robot goes to its new\n"
          "tile at its next reset. ValueError without a tiled terrain or for a bad env id.")
      .def(
          "push_links",
          [](KSimulator& s) {
            if (!s.sim->push_links()) throw nb::value_error(s.sim->last_error().c_str());
          },
          "LeggedGym-Ex's push_links: a force with components in [-simulator.max_push_force_N, max] on every link's centre of\n"
          "mass during the next physics step. ValueError for robots without links.")
      .def_prop_ro("measured_heights", [](nb::pointer_and_handle<KSimulator> s) {
        static const real kNone = 0;  // a valid pointer for the (robots, 0) view without height points
        const real* p = s.p->sim->measured_heights();
        return view2<real>(p != nullptr ? p : &kNone, s.p->robots(), static_cast<std::size_t>(s.p->sim->num_height_points()), s.h);
      }, "(num_robots, num_height_points) legged_gym's measured_heights: terrain z under each robot's height points (m)")
      .def_prop_ro("num_dofs", [](KSimulator& s) { return s.sim->num_dofs(); }, "actuated joints per robot (0: not articulated)")
      .def_prop_ro("num_feet", [](KSimulator& s) { return s.sim->num_feet(); }, "foot bodies per robot")
      .def_prop_ro("num_links", [](KSimulator& s) { return s.sim->num_links(); }, "bodies per robot")
      .def_prop_ro("feet_pos_w",
                   [](nb::pointer_and_handle<KSimulator> s) {
                     return nb::ndarray<nb::numpy, real, nb::ndim<3>, nb::c_contig>(
                         const_cast<real*>(s.p->sim->feet_pos_w()),
                         {s.p->robots(), static_cast<std::size_t>(s.p->sim->num_feet()), std::size_t(3)}, s.h);
                   },
                   "(num_robots, num_feet, 3) foot body origins in the world (m), a view on the simulator's buffer.")
      .def_prop_ro("link_contact_forces_w",
                   [](nb::pointer_and_handle<KSimulator> s) {
                     return nb::ndarray<nb::numpy, real, nb::ndim<3>, nb::c_contig>(
                         const_cast<real*>(s.p->sim->link_contact_forces_w()),
                         {s.p->robots(), static_cast<std::size_t>(s.p->sim->num_links()), std::size_t(3)}, s.h);
                   },
                   "(num_robots, num_links, 3) the ground's force on each body at the last physics step (N, world).")
      .def(
          "reset_dofs",
          [](KSimulator& s, const std::vector<int>& ids, nb::handle pos, nb::handle vel) {
            const std::size_t rows = ids.size() * static_cast<std::size_t>(s.sim->robots_per_env());
            const std::size_t nd = static_cast<std::size_t>(s.sim->num_dofs());
            if (nd == 0) throw nb::value_error("reset_dofs: the robot has no joints (robot kind articulated only)");
            const char* dims = "(len(env_ids) * robots_per_env, num_dofs)";
            const real* p = checked_actions<real>(pos, rows, nd, "dof_pos", dims);
            const real* v = checked_actions<real>(vel, rows, nd, "dof_vel", dims);
            bool ok = false;
            {
              nb::gil_scoped_release release;
              ok = s.sim->reset_dofs(ids.data(), static_cast<int>(ids.size()), p, v);
            }
            if (!ok) throw nb::value_error(s.sim->last_error().c_str());
          },
          "env_ids"_a, "dof_pos"_a, "dof_vel"_a,
          "legged_gym's reset_dofs: joint positions and velocities of the listed envs (arrays of the real dtype).\n"
          "ValueError (nothing changed) for a bad env id, a wrong shape or non-finite values.")
      .def_prop_ro("lidar_ranges_m",
                   [](nb::pointer_and_handle<KSimulator> s) {
                     return view2<real>(s.p->sim->lidar_ranges_m(), s.p->robots(),
                                        static_cast<std::size_t>(s.p->sim->lidar_beams()), s.h);
                   })
      .def_prop_ro("reset_buf", [](nb::pointer_and_handle<KSimulator> s) {
        return Array1<bool>(reinterpret_cast<bool*>(const_cast<std::uint8_t*>(s.p->sim->reset_buf())),
                            {static_cast<std::size_t>(s.p->sim->num_envs())}, s.h);
      })
      .def_prop_ro("num_range_images", [](KSimulator& s) { return s.sim->num_range_images(); },
                   "Ray-sensor images per robot (rigid: the lidar / ToF / camera sensors in robot.sensors order, "
                   "IMUs skipped; planar: 1 with a 2-D lidar, else 0).")
      .def(
          "range_images",
          [](nb::pointer_and_handle<KSimulator> s, int k) {
            return image_view3<real>(range_layout(*s.p->sim, k), s.p->robots(), s.h);
          },
          "k"_a = 0,
          "Image k of every robot as a read-only (num_robots, height, width) view of the simulator's buffer (no copy;\n"
          "robot index = env * robots_per_env + r, so (num_envs, H, W) with one robot per env). Element [i, r, c]:\n"
          "row 0 the top, column 0 the leftmost (body +y side); strides from the C++ RangeImage's row_step / col_step\n"
          "(planar: a negative column stride over its clockwise-first lidar row). Rewritten in place whenever the\n"
          "sensors render (every step at the sensor's rate, at resets, update_sensors()); the data pointer is fixed\n"
          "for the simulator's life and the array keeps the simulator alive. Metres (or [0, 1] where the sensor\n"
          "normalises: range_image_info(k)['max_range_m'] is then 1); negative, non-finite or >= max_range_m: no return.")
      .def(
          "range_image",
          [](nb::pointer_and_handle<KSimulator> s, int robot, int k) {
            check_robot(*s.p->sim, robot);
            return image_view2<real>(range_layout(*s.p->sim, k), robot, s.h);
          },
          "robot"_a, "k"_a = 0, "Robot `robot`'s image k as a read-only (height, width) view (range_images(k)[robot]).")
      .def(
          "range_image_info",
          [](KSimulator& s, int k) {
            check_image_index(*s.sim, k);
            const ks::RangeImage im = s.sim->range_image(0, k);
            nb::dict d;
            d["height"] = im.height;
            d["width"] = im.width;
            d["row_step"] = static_cast<std::int64_t>(im.row_step);
            d["col_step"] = static_cast<std::int64_t>(im.col_step);
            d["max_range_m"] = static_cast<double>(im.max_range_m);
            d["horizontal_fov_rad"] = static_cast<double>(im.horizontal_fov_rad);
            return d;
          },
          "k"_a = 0, "Image k's RangeImage fields: height, width, row_step, col_step (elements), max_range_m, horizontal_fov_rad.")
      .def(
          "range_image_rays", [](KSimulator& s, int k) { return range_image_rays(*s.sim, k); }, "k"_a = 0,
          "Rigid only: image k's rays, to turn pixels into points (the viewer's point clouds): a dict with name,\n"
          "kind (lidar | camera), dirs_s (height, width, 3: unit ray directions in the sensor frame, pixel for pixel\n"
          "with range_images(k)), depth_scale (height, width: a depth camera's pixel is range along the ray times\n"
          "this), depth (bool), value_scale_m (metres per pixel unit: max_range_m when the sensor normalises, else 1),\n"
          "min_range_m, max_range_m (metres). A pixel v is a return when min <= v * value_scale_m < max; its point\n"
          "in the sensor frame is v * value_scale_m / depth_scale * dirs_s (see sensor_mounts for the sensor pose).")
      .def(
          "sensor_mounts", [](KSimulator& s, int k) { return sensor_mounts(*s.sim, k); }, "k"_a = 0,
          "Rigid only: (position_b (num_robots, 3), orientation_bs_xyzw (num_robots, 4)), each robot's mount of image k\n"
          "(drawn at its environment's last reset): sensor point in the world = p_wb + R_wb (position_b + R_bs x_s).")
      .def(
          "world_data", [](nb::pointer_and_handle<KSimulator> s) { return world_data_views(*s.p->sim, s.h); },
          "Rigid only: the World's data (sim/world_data.hpp) as read-only numpy views without copies, a dict:\n"
          "position_w, orientation_xyzw, linvel_w, angvel_b (num_robots, 3|4; strided over the state rows),\n"
          "contact_force_w, contact_torque_b, target_w, setpoint_w (num_robots, 3), actions (num_robots, kMaxActionDim),\n"
          "crashed (num_robots,), episode_step, num_obstacles (num_envs,), lower_w, upper_w (num_envs, 3),\n"
          "obstacle_position_w (num_envs, capacity, 3) and measured_heights (num_robots, points) where present.\n"
          "The arrays are sized once: the views stay valid, and change in place, as the simulator steps.")
      .def(
          "segmentation_images",
          [](nb::pointer_and_handle<KSimulator> s, int k) {
            return image_view3<std::int32_t>(segmentation_layout(*s.p->sim, k), s.p->robots(), s.h);
          },
          "k"_a = 0,
          "Rigid only: image k's segmentation (obstacle semantic id, 0 the ground, -1 no hit) as a read-only int32\n"
          "(num_robots, height, width) view, pixel for pixel with range_images(k); planar raises ValueError.")
      .def(
          "env_bounds",
          [](KSimulator& s, int env) {
            if (env < 0 || env >= s.sim->num_envs())
              throw nb::value_error(("env: expected an env index in [0, " + std::to_string(s.sim->num_envs()) + "), got " +
                                     std::to_string(env))
                                        .c_str());
            kestrel::Vec3 lo, hi;
            s.sim->env_bounds(env, lo, hi);
            return nb::make_tuple(nb::make_tuple(static_cast<double>(lo.x()), static_cast<double>(lo.y()), static_cast<double>(lo.z())),
                                  nb::make_tuple(static_cast<double>(hi.x()), static_cast<double>(hi.y()), static_cast<double>(hi.z())));
          },
          "env"_a, "The environment's (lower, upper) bounds in the world frame for its current episode (m).")
      .def(
          "reset_root_states",
          [](KSimulator& s, const std::vector<int>& ids, nb::handle pos, nb::handle quat, nb::handle lin, nb::handle ang) {
            for (int id : ids)
              if (id < 0 || id >= s.sim->num_envs())
                throw nb::value_error(("env_ids: expected ids in [0, " + std::to_string(s.sim->num_envs()) + "), got " + std::to_string(id)).c_str());
            const std::size_t rows = ids.size() * static_cast<std::size_t>(s.sim->robots_per_env());
            const char* dims = "(len(env_ids) * robots_per_env, n)";
            const real* p = checked_actions<real>(pos, rows, 3, "pos_w", dims);
            const real* q = checked_actions<real>(quat, rows, 4, "quat_xyzw", dims);
            std::vector<real> zeros(rows * 3, real(0));
            const real* v = lin.is_none() ? zeros.data() : checked_actions<real>(lin, rows, 3, "lin_vel_w", dims);
            const real* w = ang.is_none() ? zeros.data() : checked_actions<real>(ang, rows, 3, "ang_vel_w", dims);
            bool ok = false;
            {
              nb::gil_scoped_release release;
              ok = s.sim->reset_root_states(ids.data(), static_cast<int>(ids.size()), p, q, v, w);
            }
            if (!ok) throw nb::value_error(s.sim->last_error().c_str());
          },
          "env_ids"_a, "pos_w"_a, "quat_xyzw"_a, "lin_vel_w"_a = nb::none(), "ang_vel_w"_a = nb::none(),
          "Puts exact root states for the listed envs (robots_per_env rows each; arrays of the real dtype,\n"
          "kestrel._core.real_dtype): positions (m, world), unit quaternions xyzw, velocities (world; None = 0).\n"
          "The sensor images are re-rendered at the next step or update_sensors(). ValueError (nothing changed)\n"
          "for a state the backend cannot represent.")
      .def(
          "obstacles", [](KSimulator& s, int env) { return obstacle_arrays(*s.sim, env); }, "env"_a = 0,
          "Rigid only: environment env's obstacles in use as a dict of copied arrays: type (0 sphere, 1 box,\n"
          "2 capsule, 3 cylinder, 4 convex hull), radius_m, half_length_m (capsule / cylinder, axis = local z),\n"
          "half_extents_m (box), position_w, orientation_xyzw, semantic_id, asset_kind, asset_class, and\n"
          "hull_vertices_b (a list: each convex hull's body-frame vertices, (0, 3) for other shapes).")
      .def("scene_info", [](KSimulator& s) { return scene_info(*s.sim); },
           "What does not change while the simulator lives: the robot's name, kind, collision shape, rotor hubs,\n"
           "axes and spin directions (body frame), the terrain (heights_m (ny, nx), height_spacing_m,\n"
           "height_corner_w for a height field), the height points' body-frame offsets, the link names.")
      .def("motor_state", [](KSimulator& s) { return motor_arrays(*s.sim); },
           "Rigid only: (thrust_N (num_robots, rotors) float64, faults (num_robots,) uint32): each motor's thrust\n"
           "after the last physics step and the latched fault bits of its chain (kestrel.FAULT_BITS names them).");

  nb::class_<ScriptedJointTargets>(m, "ScriptedJointTargets",
                                   "`kestrel run`'s random joint targets for articulated robots, the C++ run's draws.")
      .def(
          "__init__",
          [](ScriptedJointTargets* self, KSimulator& s) {
            new (self) ScriptedJointTargets();
            self->robots = s.robots();
            self->dofs = static_cast<std::size_t>(s.sim->num_dofs());
            if (self->dofs == 0) throw nb::value_error("sim: ScriptedJointTargets needs an articulated robot (num_dofs > 0)");
            for (std::size_t i = 0; i < self->robots; ++i)
              self->rng.emplace_back(s.sim->config().seed, static_cast<std::uint32_t>(i), ks::kPurposeScriptedTargets);
            self->actions.assign(self->robots * self->dofs, real(0));
          },
          "sim"_a)
      .def(
          "next",
          [](ScriptedJointTargets& t) {
            if (t.step++ % 25 == 0)
              for (std::size_t i = 0; i < t.robots; ++i)
                for (std::size_t j = 0; j < t.dofs; ++j) t.actions[i * t.dofs + j] = t.rng[i].uniform(-1, 1);
            std::vector<real> copy(t.actions);
            return owned_array(std::move(copy), {t.robots, t.dofs});
          },
          "The actions of the next env-step, (num_robots, num_dofs) of the real dtype.");
}
