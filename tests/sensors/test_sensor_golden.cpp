// Golden parity of the ray patterns with Aerial Gym (golden/sensor_rays.json): every stored lidar
// and camera direction within abs 2e-6 per component, and the camera's depth_over_range factor.
// The file is streamed (json_pull); each ray is recomputed on its own (lidar_ray / camera_ray), so
// the MCU never holds a 64 x 512 table.
#include <cstring>

#include "json_pull.hpp"
#include "kestrel/sensors/ray_sensor.hpp"
#include "ktest.hpp"
#include "test_io.hpp"

using namespace kestrel;
using namespace kestrel::sensors;

namespace {
constexpr double kTol = 2e-6;  // conventions.recommended_tolerance.abs
}

KTEST(SensorGolden, RayDirectionsAndDepthFactorsMatchReference) {
  ktest::JsonReader r;
  KASSERT_TRUE(r.open(ktest::golden_path("sensor_rays.json")));
  KASSERT_TRUE(r.begin_object());
  KASSERT_TRUE(r.find_key("sensors"));
  KASSERT_TRUE(r.begin_array());
  int sensors = 0, lidar_rays_checked = 0, camera_rays_checked = 0;
  while (r.next_element()) {
    KASSERT_TRUE(r.begin_object());
    char kind[32] = {0};
    LidarParams lp;
    CameraParams cp;
    char key[64];
    while (r.next_key(key, sizeof key)) {
      float v2[2];
      if (std::strcmp(key, "kind") == 0) {
        KASSERT_TRUE(r.read_string(kind, sizeof kind));
      } else if (std::strcmp(key, "height") == 0) {
        int h = 0;
        KASSERT_TRUE(r.read_int(h));
        lp.height = cp.height = static_cast<std::uint32_t>(h);
      } else if (std::strcmp(key, "width") == 0) {
        int w = 0;
        KASSERT_TRUE(r.read_int(w));
        lp.width = cp.width = static_cast<std::uint32_t>(w);
      } else if (std::strcmp(key, "horizontal_fov_deg") == 0 && std::strcmp(kind, "lidar") == 0) {
        KASSERT_EQ(r.read_numbers(v2, 2), 2);
        lp.horizontal_fov_deg_min = static_cast<real>(v2[0]);
        lp.horizontal_fov_deg_max = static_cast<real>(v2[1]);
      } else if (std::strcmp(key, "horizontal_fov_deg") == 0) {
        float f = 0;
        KASSERT_TRUE(r.read_float(f));
        cp.horizontal_fov_deg = static_cast<real>(f);
      } else if (std::strcmp(key, "vertical_fov_deg") == 0) {
        KASSERT_EQ(r.read_numbers(v2, 2), 2);
        lp.vertical_fov_deg_min = static_cast<real>(v2[0]);
        lp.vertical_fov_deg_max = static_cast<real>(v2[1]);
      } else if (std::strcmp(key, "calculate_depth") == 0) {
        bool b = false;
        KASSERT_TRUE(r.read_bool(b));
        cp.calculate_depth = b;
      } else if (std::strcmp(key, "rays") == 0) {
        const bool is_lidar = std::strcmp(kind, "lidar") == 0;
        KASSERT_TRUE(r.begin_array());
        while (r.next_element()) {
          KASSERT_TRUE(r.begin_object());
          int row = -1, col = -1;
          float dir[3] = {0, 0, 0};
          float dor = -1;
          bool have_dir = false, have_dor = false;
          char rk[64];
          while (r.next_key(rk, sizeof rk)) {
            if (std::strcmp(rk, "row") == 0) {
              KASSERT_TRUE(r.read_int(row));
            } else if (std::strcmp(rk, "col") == 0) {
              KASSERT_TRUE(r.read_int(col));
            } else if (std::strcmp(rk, "dir_sensor") == 0) {
              KASSERT_EQ(r.read_numbers(dir, 3), 3);
              have_dir = true;
            } else if (std::strcmp(rk, "depth_over_range") == 0) {
              KASSERT_TRUE(r.read_float(dor));
              have_dor = true;
            } else {
              KASSERT_TRUE(r.skip_value());
            }
          }
          KASSERT_TRUE(have_dir && row >= 0 && col >= 0);
          real d[3];
          real scale = 1;
          if (is_lidar) {
            lidar_ray(lp, static_cast<std::uint32_t>(row), static_cast<std::uint32_t>(col), d);
            ++lidar_rays_checked;
          } else {
            camera_ray(cp, static_cast<std::uint32_t>(row), static_cast<std::uint32_t>(col), d, scale);
            KASSERT_TRUE(have_dor);
            KEXPECT_CLOSE(scale, dor, kTol, 0, "depth_over_range");
            ++camera_rays_checked;
          }
          for (int k = 0; k < 3; ++k) KEXPECT_CLOSE(d[k], dir[k], kTol, 0, "dir_sensor");
        }
      } else {
        KASSERT_TRUE(r.skip_value());
      }
    }
    ++sensors;
  }
  KEXPECT_TRUE(r.ok());
  KEXPECT_EQ(sensors, 3);
  KEXPECT_EQ(lidar_rays_checked, 6 * 9 + 128);
  KEXPECT_EQ(camera_rays_checked, 144);
}

KTEST(SensorGolden, FullDomeEndColumnsCoincide) {
  // Quirk 12: a 360 deg lidar samples both +180 and -180 deg.
  const LidarParams p = lidar_preset_osdome_64();
  real a[3], b[3];
  lidar_ray(p, 10, 0, a);
  lidar_ray(p, 10, p.width - 1, b);
  for (int k = 0; k < 3; ++k) KEXPECT_NEAR(a[k], b[k], 1e-6);
}
