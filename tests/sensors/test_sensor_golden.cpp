// Golden parity of the ray patterns with Aerial Gym (golden/sensor_rays.json): every stored lidar
// and camera direction within the file's tolerance (abs 2e-6 per component in the public set), and
// the camera's depth_over_range factor. Counts come from the file: any number of sensors and rays,
// but at least one lidar and one camera, each with rays, so an empty or truncated file fails.
// The file is streamed (json_pull); each ray is recomputed on its own (lidar_ray / camera_ray), so
// the MCU never holds a 64 x 512 table.
#include <cstring>

#include "golden_tol.hpp"
#include "json_pull.hpp"
#include "kestrel/sensors/ray_sensor.hpp"
#include "ktest.hpp"
#include "test_io.hpp"

using namespace kestrel;
using namespace kestrel::sensors;

KTEST(SensorGolden, RayDirectionsAndDepthFactorsMatchReference) {
  ktest::JsonReader r;
  KASSERT_TRUE(r.open(ktest::golden_path("sensor_rays.json")));
  KASSERT_TRUE(r.begin_object());
  ktest::GoldenTol tol = {2e-6, 0};  // unless conventions.recommended_tolerance says otherwise
  KASSERT_TRUE(r.find_key("conventions"));  // listed first
  KASSERT_TRUE(ktest::read_conventions_tolerance(r, [&](ktest::JsonReader& t) { return ktest::read_tolerance(t, tol); }));
  KASSERT_TRUE(r.find_key("sensors"));
  KASSERT_TRUE(r.begin_array());
  int lidars = 0, cameras = 0, rays_in_file = 0, lidar_rays_checked = 0, camera_rays_checked = 0;
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
        KEXPECT_TRUE(is_lidar || std::strcmp(kind, "pinhole_camera") == 0);
        lidars += is_lidar;
        cameras += !is_lidar;
        const int rays_before = rays_in_file;
        KASSERT_TRUE(r.begin_array());
        while (r.next_element()) {
          ++rays_in_file;
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
            KEXPECT_CLOSE(scale, dor, tol.abs, tol.rel, "depth_over_range");
            ++camera_rays_checked;
          }
          for (int k = 0; k < 3; ++k) KEXPECT_CLOSE(d[k], dir[k], tol.abs, tol.rel, "dir_sensor");
        }
        KEXPECT_GE(rays_in_file - rays_before, 1);  // every sensor lists rays
      } else {
        KASSERT_TRUE(r.skip_value());
      }
    }
  }
  KEXPECT_TRUE(r.ok());
  KEXPECT_GE(lidars, 1);
  KEXPECT_GE(cameras, 1);
  KEXPECT_GE(lidar_rays_checked, 1);
  KEXPECT_GE(camera_rays_checked, 1);
  KEXPECT_EQ(lidar_rays_checked + camera_rays_checked, rays_in_file);
}

KTEST(SensorGolden, FullDomeEndColumnsCoincide) {
  // Quirk 12: a 360 deg lidar samples both +180 and -180 deg.
  const LidarParams p = lidar_preset_osdome_64();
  real a[3], b[3];
  lidar_ray(p, 10, 0, a);
  lidar_ray(p, 10, p.width - 1, b);
  for (int k = 0; k < 3; ++k) KEXPECT_NEAR(a[k], b[k], 1e-6);
}
