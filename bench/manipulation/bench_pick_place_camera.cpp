// The SO-101 pick-and-place cameras (sim/pick_place_camera.hpp) on one core: frames per second
// and million rays per second of the front and the wrist camera at 640 x 480 (RGB + depth +
// segmentation every frame), at the home pose and with the cube held after a scripted grasp,
// and, with an output folder, their images after the grasp as PNGs (RGB, and depth in mm as
// 16-bit grey).
//
//   kestrel_bench_pick_place_camera [seconds per case=2] [png folder] [csv path]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "kestrel/sim/pick_place.hpp"
#include "kestrel/sim/pick_place_camera.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {

struct Timing {
  double fps = 0, mrays = 0;
  long frames = 0;
};

Timing time_camera(const PickPlaceWorld& w, const CameraSpec& cam, double seconds, std::vector<std::uint8_t>& rgb,
                   std::vector<float>& depth, std::vector<std::uint8_t>& seg) {
  using clock = std::chrono::steady_clock;
  Timing t;
  for (int k = 0; k < 3; ++k)  // warm the caches
    if (render_camera(w, cam, rgb.data(), depth.data(), seg.data()) != Status::ok) return t;
  const auto t0 = clock::now();
  double el = 0;
  do {
    for (int k = 0; k < 10; ++k) (void)render_camera(w, cam, rgb.data(), depth.data(), seg.data());
    t.frames += 10;
    el = std::chrono::duration<double>(clock::now() - t0).count();
  } while (el < seconds);
  t.fps = static_cast<double>(t.frames) / el;
  t.mrays = t.fps * cam.width * cam.height / 1e6;
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 2.0;
  const std::string png_dir = argc > 2 ? argv[2] : "";
  const char* csv_path = argc > 3 ? argv[3] : nullptr;
  PickPlaceConfig cfg;
  PickPlaceWorld w;
  std::string err;
  if (!w.init(cfg, 1, 0, err)) {
    std::fprintf(stderr, "%s\n", err.c_str());
    return 1;
  }
  const int W = 640, H = 480;
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(W) * H * 3), seg(static_cast<std::size_t>(W) * H);
  std::vector<float> depth(static_cast<std::size_t>(W) * H);
  const CameraSpec front = front_camera(W, H), wrist = wrist_camera(w, W, H);
  std::FILE* csv = csv_path != nullptr ? std::fopen(csv_path, "w") : nullptr;
  if (csv != nullptr) std::fprintf(csv, "camera,state,width,height,frames,frames_per_s,mrays_per_s\n");
  auto report = [&](const char* name, const char* state, const CameraSpec& cam) {
    const Timing t = time_camera(w, cam, seconds, rgb, depth, seg);
    std::printf("%-5s camera, %-7s: %d x %d, %6ld frames, %7.1f frames/s, %6.2f Mrays/s (one core)\n", name, state, cam.width,
                cam.height, t.frames, t.fps, t.mrays);
    if (csv != nullptr) std::fprintf(csv, "%s,%s,%d,%d,%ld,%.1f,%.2f\n", name, state, cam.width, cam.height, t.frames, t.fps, t.mrays);
  };
  report("front", "home", front);
  report("wrist", "home", wrist);

  // The scripted pick and place up to the lift: the cube held between the pads.
  ScriptedPickPlace s(w);
  real a[PickPlaceWorld::kJoints];
  int actions = 0;
  while (!s.done() && s.phase() <= 3 && actions < 400) {
    s.act(a);
    (void)w.step(a);
    ++actions;
  }
  std::printf("after %d actions (phase %d): cube at (%.3f, %.3f, %.3f) m, grip %.2f N\n", actions, s.phase(),
              static_cast<double>(w.state().cube_pos_w[0]), static_cast<double>(w.state().cube_pos_w[1]),
              static_cast<double>(w.state().cube_pos_w[2]), static_cast<double>(w.grip_force_N()));
  report("front", "grasped", front);
  report("wrist", "grasped", wrist);
  if (csv != nullptr) std::fclose(csv);

  if (!png_dir.empty()) {
    const struct {
      const char* name;
      const CameraSpec* cam;
    } cams[2] = {{"front", &front}, {"wrist", &wrist}};
    for (const auto& c : cams) {
      if (render_camera(w, *c.cam, rgb.data(), depth.data(), seg.data()) != Status::ok) return 1;
      const std::string base = png_dir + "/camera_" + c.name;
      if (!write_camera_pngs(base + "_rgb.png", base + "_depth_mm.png", W, H, rgb.data(), depth.data(), err)) {
        std::fprintf(stderr, "%s\n", err.c_str());
        return 1;
      }
      std::printf("wrote %s_rgb.png, %s_depth_mm.png\n", base.c_str(), base.c_str());
    }
  }
  return 0;
}
