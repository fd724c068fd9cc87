// Terrain (sim/terrain.hpp): height fields from YAML lists, PGM/PNG images and legged_gym's
// generators; triangle-mesh terrain; contact at known heights and normals; measured_heights;
// sensor rays against the terrain; scenario errors naming the file and field; no heap in the step.
// Also the scenario-side leftovers of issue 4: mesh asset classes from YAML and rotating obstacles.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "heap_counter.hpp"
#include "kestrel/kernel/quaternion.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/terrain.hpp"
#include "kestrel/sim/world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {
const std::string kData = std::string(KESTREL_SIM_TEST_DIR) + "/data/";

std::unique_ptr<World> build(const WorldConfig& c) {
  std::string err;
  auto w = World::create(c, err);
  EXPECT_TRUE(w) << err;
  return w;
}
WorldConfig scenario(const std::string& yaml) {
  WorldConfig c;
  std::string err;
  EXPECT_TRUE(load_scenario_string(yaml, "test.yaml", c, err)) << err;
  return c;
}
std::unique_ptr<Terrain> make_terrain(const TerrainConfig& t, std::uint64_t seed = 0) {
  std::unique_ptr<Terrain> out;
  std::string err;
  EXPECT_TRUE(Terrain::build(t, seed, out, err)) << err;
  return out;
}
TerrainConfig slope_config(real slope) {
  TerrainConfig t;
  t.type = TerrainType::heightfield;
  t.procedural = "slope";
  t.slope = slope;
  t.length_x_m = t.width_y_m = 8;
  t.horizontal_scale_m = 0.1_r;
  t.origin_m = Vec3(0, 0, 0.5_r);
  return t;
}
Shape sphere_at(const Vec3& p, real r) {
  Shape s;
  s.type = ShapeType::sphere;
  s.radius_m = r;
  s.position_w = p;
  return s;
}
// A robot that falls with its motors off and rests (direct motor commands, zero thrust).
WorldConfig resting_robot(const std::string& terrain_yaml, const Vec3& start_ratio) {
  WorldConfig c = scenario("env: {name: empty, num_envs: 1, collision_force_threshold: 1000, reset_on_collision: false,\n"
                           "      terrain: " + terrain_yaml + "}\n"
                           "controller: direct_motor_control\n"
                           "task: {name: hover, episode_len_env_steps: 100000}\n");
  c.robot.min_init_position_ratio = c.robot.max_init_position_ratio = start_ratio;
  c.robot.max_init_yaw_rad = 0;
  c.task.clearance_m = 0;
  return c;
}
void motors_off(World& w) {
  for (int env = 0; env < w.num_envs(); ++env) {
    real* a = w.action(env, 0);
    for (int m = 0; m < 4; ++m) a[m] = 0;
  }
}
}  // namespace

TEST(SimTerrain, ProceduralSlopeStairsAndRandomHeights) {
  // slope: h = origin z + slope * (x - x0), x0 the grid's first column.
  auto t = make_terrain(slope_config(0.3_r));
  EXPECT_EQ(t->nx(), 81);
  EXPECT_EQ(t->ny(), 81);
  EXPECT_NEAR(t->corner_w()[0], -4, 1e-6);
  for (real x : {-3.95_r, -1.23_r, 0.0_r, 2.71_r})
    for (real y : {-2.5_r, 0.37_r, 3.9_r}) EXPECT_NEAR(t->height_at(x, y), 0.5_r + 0.3_r * (x + 4), 2e-5) << x << " " << y;
  // Outside the grid: the nearest edge (legged_gym clips its indices).
  EXPECT_NEAR(t->height_at(10, 0), 0.5_r + 0.3_r * 8, 2e-5);
  // stairs: step k of width 0.3 m at (k + 1) * 0.1 m.
  TerrainConfig s;
  s.type = TerrainType::heightfield;
  s.procedural = "stairs";
  s.length_x_m = 3;
  s.width_y_m = 1;
  auto st = make_terrain(s);
  EXPECT_NEAR(st->heights()[0], 0.1_r, 1e-6);
  EXPECT_NEAR(st->heights()[2], 0.1_r, 1e-6);
  EXPECT_NEAR(st->heights()[3], 0.2_r, 1e-6);
  EXPECT_NEAR(st->heights()[29], 1.0_r, 1e-6);
  // random_uniform: heights within [min, max], on the step grid at the coarse samples,
  // reproducible for a seed and different for another.
  TerrainConfig r;
  r.type = TerrainType::heightfield;
  r.procedural = "random_uniform";
  auto r1 = make_terrain(r, 5), r2 = make_terrain(r, 5), r3 = make_terrain(r, 6);
  EXPECT_EQ(r1->heights(), r2->heights());
  EXPECT_NE(r1->heights(), r3->heights());
  real lo = 1, hi = -1;
  for (real h : r1->heights()) {
    lo = std::min(lo, h);
    hi = std::max(hi, h);
  }
  EXPECT_GE(lo, -0.05_r - 1e-6_r);
  EXPECT_LE(hi, 0.05_r + 1e-6_r);
  EXPECT_GT(hi - lo, 0.03_r);  // not flat
  const real corner = r1->heights()[0];
  EXPECT_NEAR(std::round((corner + 0.05_r) / 0.005_r) * 0.005_r - 0.05_r, corner, 1e-5);
  // pyramid_stairs: the middle is the highest, the border the lowest.
  TerrainConfig p;
  p.type = TerrainType::heightfield;
  p.procedural = "pyramid_stairs";
  p.length_x_m = p.width_y_m = 4;
  auto ps = make_terrain(p);
  // 41 samples: rings of 3 samples while the inside is wider than the 10-sample platform:
  // 41 -> 35 -> 29 -> 23 -> 17 -> 11 -> 5, six rings of 0.1 m.
  EXPECT_NEAR(ps->height_at(0, 0), 0.6_r, 1e-5);
  EXPECT_NEAR(ps->height_at(-1.95_r, 0), 0, 1e-5);
}

TEST(SimTerrain, CurriculumTilesFollowLeggedGymsDifficultyAndTypes) {
  // 3 levels x 5 types of 8 m x 8 m tiles (80 x 80 samples) in a 2 m border, legged_gym's default
  // proportions [0.1, 0.1, 0.35, 0.25, 0.2]: column j's choice j / 5 + 0.001 makes columns 0..4 a
  // smooth slope (negative: choice < 0.05), stairs up (a pit: choice < 0.55), stairs up, stairs
  // down, discrete obstacles; level i's difficulty is i / 3.
  TerrainConfig c;
  c.type = TerrainType::heightfield;
  c.procedural = "curriculum";
  c.num_rows = 3;
  c.num_cols = 5;
  c.border_size_m = 2;
  auto t = make_terrain(c, 7);
  ASSERT_EQ(t->tile_rows(), 3);
  ASSERT_EQ(t->tile_cols(), 5);
  EXPECT_EQ(t->nx(), 3 * 80 + 2 * 20);
  EXPECT_EQ(t->ny(), 5 * 80 + 2 * 20);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 5; ++j) {
      // Tile centres: corner + (border + (i + 1/2) tile) in x, likewise in y.
      EXPECT_NEAR(t->tile_origin(i, j)[0], t->corner_w()[0] + 2 + (i + 0.5) * 8, 1e-4);
      EXPECT_NEAR(t->tile_origin(i, j)[1], t->corner_w()[1] + 2 + (j + 0.5) * 8, 1e-4);
    }
  EXPECT_EQ(t->heights()[0], 0);  // the border is flat
  for (int i = 0; i < 3; ++i) {
    const double d = i / 3.0;
    // Smooth slope, negative: the platform sits at the pyramid's height at its edge,
    // slope x (tile / 2) x ((4 - 1.5) / 4)^2, below the border.
    EXPECT_NEAR(t->tile_origin(i, 0)[2], -0.4 * d * 4 * 0.390625, 1e-5) << i;
    // Stairs of 3 samples (0.31 m) until the 30-sample (3 m) platform: 9 steps of
    // 0.05 + 0.18 d, down into the pit (stairs up) or up onto the pyramid (stairs down).
    EXPECT_NEAR(t->tile_origin(i, 1)[2], -9 * (0.05 + 0.18 * d), 1e-5) << i;
    EXPECT_NEAR(t->tile_origin(i, 2)[2], -9 * (0.05 + 0.18 * d), 1e-5) << i;
    EXPECT_NEAR(t->tile_origin(i, 3)[2], 9 * (0.05 + 0.18 * d), 1e-5) << i;
    EXPECT_NEAR(t->tile_origin(i, 4)[2], 0, 1e-6) << i;  // the obstacles' levelled platform
    // Discrete obstacles: every height is 0 or one of +-h, +-h/2 with h = 0.05 + 0.2 d.
    const double h = 0.05 + 0.2 * d;
    int raised = 0;
    for (int b = 0; b < 80; ++b)
      for (int a = 0; a < 80; ++a) {
        const real z = t->heights()[static_cast<std::size_t>(20 + 4 * 80 + b) * static_cast<std::size_t>(t->nx()) +
                                    static_cast<std::size_t>(20 + i * 80 + a)];
        const double az = std::fabs(static_cast<double>(z));
        EXPECT_TRUE(az < 1e-6 || std::fabs(az - h) < 1e-5 || std::fabs(az - h / 2) < 1e-5) << z;
        raised += az > 1e-6 ? 1 : 0;
      }
    EXPECT_GT(raised, 400) << i;  // 20 rectangles of >= 1 m x 1 m, partly overlapping
  }
  // The level-0 slope is flat and the hardest stairs are the steepest.
  EXPECT_NEAR(t->height_at(t->tile_origin(0, 0)[0] + 3.5_r, t->tile_origin(0, 0)[1]), 0, 1e-6);
  // Reproducible for a seed; randomized tiles differ between seeds.
  auto t2 = make_terrain(c, 7);
  EXPECT_EQ(t->heights(), t2->heights());
  c.procedural = "randomized";
  auto r1 = make_terrain(c, 7), r2 = make_terrain(c, 8);
  EXPECT_NE(r1->heights(), r2->heights());
  EXPECT_EQ(r1->tile_rows(), 3);
  // Other terrains have no tiles; tiles too small for the platform are refused by name.
  EXPECT_EQ(make_terrain(slope_config(0.1_r))->tile_rows(), 0);
  c.tile_length_m = 3;
  std::unique_ptr<Terrain> bad;
  std::string err;
  EXPECT_FALSE(Terrain::build(c, 1, bad, err));
  EXPECT_NE(err.find("tile_length_m"), std::string::npos) << err;
}

TEST(SimTerrain, HeightmapImagesPgmAndPng) {
  TerrainConfig t;
  t.type = TerrainType::heightfield;
  t.image_file = kData + "heightmap.pgm";
  t.vertical_scale_m = 0.01_r;
  t.horizontal_scale_m = 1;
  auto a = make_terrain(t);
  ASSERT_EQ(a->nx(), 3);
  ASSERT_EQ(a->ny(), 2);
  // Image row 0 (10 20 30) is the largest y: heights row j = 1.
  const real expect[6] = {0.4_r, 0.5_r, 0.6_r, 0.1_r, 0.2_r, 0.3_r};
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(a->heights()[static_cast<std::size_t>(i)], expect[i], 1e-6) << i;
  t.image_file = kData + "heightmap16.png";
  t.vertical_scale_m = 0.001_r;
  auto b = make_terrain(t);
  ASSERT_EQ(b->nx(), 3);
  const real expect16[6] = {4, 5, 65.535_r, 1, 2, 3};
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(b->heights()[static_cast<std::size_t>(i)], expect16[i], 1e-4) << i;
}

TEST(SimTerrain, SphereOnSlopeGetsTheAnalyticNormalAndDepth) {
  const real s = 0.3_r, r = 0.2_r, depth = 0.004_r;
  auto t = make_terrain(slope_config(s));
  const Vec3 n = Vec3(-s, 0, 1).normalized();
  for (const Vec3& xy : {Vec3(0.03_r, 0.07_r, 0), Vec3(-1.5_r, 2.2_r, 0), Vec3(1.0_r, -1.0_r, 0)}) {
    // Centre at distance r - depth from the plane along its normal.
    const Vec3 foot(xy[0], xy[1], t->height_at(xy[0], xy[1]));
    Contact k[kMaxTerrainContacts];
    const int nk = t->collide(sphere_at(foot + (r - depth) * n, r), r, k);
    ASSERT_EQ(nk, 1) << "coplanar cells merge into one contact";
    EXPECT_NEAR(k[0].depth_m, depth, 2e-5);
    EXPECT_NEAR(k[0].normal_w.dot(n), 1, 1e-6);
    EXPECT_NEAR((k[0].point_w - foot).norm(), 0, 1e-4);
  }
  // Clear of the surface: no contact.
  Contact k[kMaxTerrainContacts];
  EXPECT_EQ(t->collide(sphere_at(Vec3(0, 0, t->height_at(0, 0) + 0.3_r), r), r, k), 0);
  // A box resting flat on a flat field: the deepest corner, normal +z.
  TerrainConfig f;
  f.type = TerrainType::heightfield;
  f.procedural = "flat";
  f.origin_m = Vec3(0, 0, 0.25_r);
  auto flat = make_terrain(f);
  Shape box;
  box.type = ShapeType::box;
  box.half_extents_m = Vec3(0.2_r, 0.1_r, 0.05_r);
  box.position_w = Vec3(0.33_r, -0.41_r, 0.25_r + 0.05_r - 0.003_r);
  ASSERT_EQ(flat->collide(box, box.half_extents_m.norm(), k), 1);
  EXPECT_NEAR(k[0].depth_m, 0.003_r, 1e-6);
  EXPECT_NEAR(k[0].normal_w[2], 1, 1e-6);
}

TEST(SimTerrain, RobotRestsOnHeightFieldFromYamlList) {
  // A 3 x 3 field 0.8 m high everywhere, from the YAML list, 6 m sample spacing: the robot (sphere
  // r 0.2 at the centre) falls onto it and rests at 0.8 + r - m g / k.
  WorldConfig c = resting_robot("{type: heightfield, horizontal_scale_m: 6, heights_m: [[0.8, 0.8, 0.8], [0.8, 0.8, 0.8], "
                                "[0.8, 0.8, 0.8]]}",
                                Vec3(0.5_r, 0.5_r, 0.3_r));
  auto w = build(c);
  motors_off(*w);
  w->step(400);
  const RigidBodyState& st = w->robot_state(0, 0);
  EXPECT_NEAR(st.position_w[2], 0.8 + 0.2 - 0.25 * 9.81 / 2000.0, 3e-4);
  EXPECT_NEAR(w->contact_force_w(0, 0)[2], 0.25 * 9.81, 0.03);
  EXPECT_LT(st.linvel_w.norm(), 0.05);
}

TEST(SimTerrain, TriangleMeshTerrainContactAndSlidingOnSlopes) {
  // tests/sim/data/slope_terrain.obj: the plane z = 1 + 0.2 x over [-5, 5]^2.
  TerrainConfig t;
  t.type = TerrainType::trimesh;
  t.mesh_file = kData + "slope_terrain.obj";
  t.origin_m = Vec3(0, 0, 0.5_r);  // moved up by 0.5 m
  auto m = make_terrain(t);
  for (real x : {-4.0_r, -0.3_r, 2.2_r}) EXPECT_NEAR(m->height_at(x, 1.1_r), 1.5_r + 0.2_r * x, 1e-5) << x;
  const Vec3 n = Vec3(-0.2_r, 0, 1).normalized();
  const Vec3 foot(1.3_r, -0.6_r, 1.5_r + 0.2_r * 1.3_r);
  Contact k[kMaxTerrainContacts];
  ASSERT_EQ(m->collide(sphere_at(foot + 0.19_r * n, 0.2_r), 0.2_r, k), 1);
  EXPECT_NEAR(k[0].depth_m, 0.01_r, 1e-5);
  EXPECT_NEAR(k[0].normal_w.dot(n), 1, 1e-6);
  // Behind the face by more than the robot's bounding diameter: no contact (one-sided, thin).
  EXPECT_EQ(m->collide(sphere_at(foot - 0.5_r * n, 0.2_r), 0.2_r, k), 0);
  // A robot falls onto the terrain through the world. Without friction (a sphere would roll down
  // otherwise) it slides down the slope pressed onto it with m g cos(theta): the contact force is
  // along the analytic normal and the centre sits r - m g cos(theta) / k from the plane. The mesh
  // and a height field of the same plane (z = 1 + 0.2 x) give the same answer.
  for (const std::string& terrain : {"{type: trimesh, mesh_file: " + kData + "slope_terrain.obj}",
                                     std::string("{type: heightfield, procedural: slope, slope: 0.2, length_x_m: 10, width_y_m: 10}")}) {
    // Start (2, 0, 1.75): 0.15 m above the surface (bounces die out within ~0.5 s).
    WorldConfig c = resting_robot(terrain, Vec3(0.7_r, 0.5_r, 0.35_r));
    c.sim.friction_coefficient = 0;
    auto w = build(c);
    motors_off(*w);
    w->step(200);
    const RigidBodyState& st = w->robot_state(0, 0);
    EXPECT_LT(st.position_w[0], 1.0_r) << terrain;  // it slid down (-x)
    const real dist = (st.position_w[2] - (1 + 0.2_r * st.position_w[0])) * n[2];
    EXPECT_NEAR(dist, 0.2_r - 0.25_r * 9.81_r * n[2] / 2000, 1e-4) << terrain;
    const Vec3 f = w->contact_force_w(0, 0);
    EXPECT_NEAR(f.norm(), 0.25 * 9.81 * n[2], 0.01) << terrain;
    EXPECT_NEAR(f.normalized().dot(n), 1, 1e-5) << terrain;
  }
}

TEST(SimTerrain, MeasuredHeightsEqualAnalyticHeightsOnPlaneAndSlope) {
  for (int slope_case = 0; slope_case < 2; ++slope_case) {
    const std::string terrain = slope_case == 0 ? "{type: plane, measure_heights: true}"
                                                : "{type: heightfield, procedural: slope, slope: 0.25, length_x_m: 12, "
                                                  "width_y_m: 12, origin_m: [0, 0, -1], measure_heights: true, "
                                                  "measured_points_x: [-0.5, 0, 0.5, 1.0], measured_points_y: [-0.3, 0.3]}";
    WorldConfig c = scenario("env: {name: empty, num_envs: 3, terrain: " + terrain + "}\ntask: hover\n");
    c.robot.max_init_yaw_rad = kPi;  // points rotate with the yaw
    auto w = build(c);
    const int np = w->num_height_points();
    ASSERT_EQ(np, slope_case == 0 ? 17 * 11 : 8);
    w->step(3);
    for (int env = 0; env < 3; ++env) {
      const RigidBodyState& st = w->robot_state(env, 0);
      const Vec3 e = euler_xyz(st.orientation_wb);
      const real yaw = e[2];
      const real* h = w->measured_heights(env, 0);
      const std::vector<real>& px = c.env.terrain.measured_points_x_m;
      const std::vector<real>& py = c.env.terrain.measured_points_y_m;
      for (std::size_t ix = 0; ix < px.size(); ++ix)
        for (std::size_t iy = 0; iy < py.size(); ++iy) {
          const real x = st.position_w[0] + std::cos(yaw) * px[ix] - std::sin(yaw) * py[iy];
          const real expect = slope_case == 0 ? 0_r : -1 + 0.25_r * (x + 6);
          EXPECT_NEAR(h[ix * py.size() + iy], expect, 1e-4) << env << " " << ix << " " << iy;
        }
    }
  }
  // Off: no points, no storage.
  auto w = build(scenario("env: {name: empty, num_envs: 1}\n"));
  EXPECT_EQ(w->num_height_points(), 0);
}

TEST(SimTerrain, SensorRaysHitTheTerrainAtTheAnalyticDistance) {
  for (const char* terrain : {"{type: heightfield, procedural: slope, slope: 0.2, length_x_m: 10, width_y_m: 10}",
                              "{type: trimesh, mesh_file: SLOPE_OBJ}"}) {
    std::string t = terrain;
    const std::size_t at = t.find("SLOPE_OBJ");
    if (at != std::string::npos) t.replace(at, 9, kData + "slope_terrain.obj");
    WorldConfig c = scenario("env: {name: empty, num_envs: 1, terrain: " + t + "}\ntask: hover\n");
    SensorConfig cam;
    ASSERT_TRUE(registries().sensors.make("base_depth_camera", cam));
    cam.camera.mount = sensors::MountParams();
    cam.camera.mount.nominal_euler_deg = Vec3(0, 90, 0);  // looking straight down
    cam.camera.noise.enable_sensor_noise = false;
    cam.camera.range.normalize_range = false;
    cam.camera.range.set_default_out_of_range_values();
    c.robot.sensors.push_back(cam);
    auto w = build(c);
    RigidBodyState& st = w->robot_state(0, 0);
    st.position_w = Vec3(0.7_r, -0.4_r, 3.5_r);
    st.orientation_wb = Quat::Identity();
    w->render_sensors(0);
    // Heightfield: z = 0.2 (x + 5); mesh: z = 1 + 0.2 x; the same plane.
    const real ground = 1 + 0.2_r * 0.7_r;
    const std::size_t centre = static_cast<std::size_t>(w->sensor_height(0) / 2) * static_cast<std::size_t>(w->sensor_width(0)) +
                               static_cast<std::size_t>(w->sensor_width(0) / 2);
    EXPECT_NEAR(w->sensor_ranges(0, 0)[centre], 3.5_r - ground, 5e-3) << terrain;
    EXPECT_EQ(w->sensor_segmentation(0, 0)[centre], 0) << terrain;
  }
}

TEST(SimTerrain, ScenarioErrorsNameFileFieldAndAllowedValues) {
  WorldConfig c;
  std::string err;
  EXPECT_FALSE(load_scenario_string("env: {name: empty, terrain: {type: lava}}\n", "bad.yaml", c, err));
  EXPECT_NE(err.find("bad.yaml: env.terrain.type: expected one of plane, heightfield, trimesh"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("env: {name: empty, terrain: {type: heightfield, procedural: moon}}\n", "bad.yaml", c, err));
  EXPECT_NE(err.find("env.terrain.procedural: unknown generator \"moon\"; allowed: flat, slope"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("env: {name: empty, terrain: {type: heightfield, heights_m: [[0, 1], [0, 1, 2]]}}\n", "bad.yaml", c, err));
  EXPECT_NE(err.find("env.terrain.heights_m[1]: expected 2 heights"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("env: {name: empty, terrain: {type: heightfield}}\n", "bad.yaml", c, err));
  EXPECT_NE(err.find("exactly one of heights_m, image_file, procedural"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("env: {name: empty, terrain: {type: trimesh}}\n", "bad.yaml", c, err));
  EXPECT_NE(err.find("env.terrain.mesh_file: missing"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("env: {name: empty, terrain: {type: plane, roughness: 2}}\n", "bad.yaml", c, err));
  EXPECT_NE(err.find("env.terrain.roughness: unknown field; allowed:"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("env: {name: empty, terrain: {type: heightfield, procedural: slope, horizontal_scale_m: -1}}\n",
                                    "bad.yaml", c, err));
  EXPECT_NE(err.find("env.terrain.horizontal_scale_m: expected a number in"), std::string::npos) << err;
  // Files are read when the world is built: the message names the scenario, the field and the file.
  for (const char* img : {"missing.png", "rgb.png", "quad.urdf"}) {
    ASSERT_TRUE(load_scenario_string("env: {name: empty, terrain: {type: heightfield, image_file: " + kData + img + "}}\n",
                                     "scene.yaml", c, err))
        << err;
    ASSERT_FALSE(World::create(c, err)) << img;
    EXPECT_NE(err.find("scene.yaml: env.terrain.image_file: "), std::string::npos) << err;
    EXPECT_NE(err.find(img), std::string::npos) << err;
  }
  EXPECT_NE(err.find("expected .pgm or .png"), std::string::npos) << err;
  ASSERT_TRUE(load_scenario_string("env: {name: empty, terrain: {type: trimesh, mesh_file: " + kData + "nope.obj}}\n", "scene.yaml", c, err));
  ASSERT_FALSE(World::create(c, err));
  EXPECT_NE(err.find("scene.yaml: env.terrain.mesh_file: "), std::string::npos) << err;
  EXPECT_NE(err.find("nope.obj: cannot open file"), std::string::npos) << err;
}

// Fuzz finding F4: the loaders sized their pixel buffers from the header before checking it: the
// 19-byte P5 file "P5\n46341 46341\n255\n" asked for 17 GB, the 68-byte grey PNG (IHDR 1e6 x 1e6)
// for 1 TB, ending in std::bad_alloc with no message. Both are now refused from the header, with
// the file, the field and the allowed range; a plausible header with too little data too.
TEST(SimTerrain, HugeHeightmapHeadersAreRefusedBeforeAllocating) {
  for (const char* img : {"fuzz_f4_huge.pgm", "fuzz_f4_huge.png"}) {
    WorldConfig c;
    std::string err;
    ASSERT_TRUE(load_scenario_string("env: {name: empty, num_envs: 1, terrain: {type: heightfield, image_file: " + kData + img + "}}\n",
                                     "scene.yaml", c, err))
        << err;
    kestrel::test::HeapCounter heap;
    ASSERT_FALSE(World::create(c, err)) << img;
    EXPECT_LT(heap.largest_allocation(), 64u * 1024 * 1024) << img;  // refused from the header: no pixel buffer
    EXPECT_NE(err.find("scene.yaml: env.terrain.image_file: "), std::string::npos) << err;
    EXPECT_NE(err.find(img), std::string::npos) << err;
    EXPECT_NE(err.find("width x height <= 67108864 (kMaxHeightmapSamples"), std::string::npos) << err;
  }
  // A header within the cap whose data is missing: refused before the buffer, naming the sizes.
  const std::string dir = ::testing::TempDir();
  const std::string path = dir + "/kestrel_truncated.pgm";
  {
    FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fputs("P5\n4000 4000\n65535\n0123456789", f);
    std::fclose(f);
  }
  WorldConfig c;
  std::string err;
  ASSERT_TRUE(load_scenario_string("env: {name: empty, num_envs: 1, terrain: {type: heightfield, image_file: " + path + "}}\n",
                                   "scene.yaml", c, err));
  kestrel::test::HeapCounter heap;
  ASSERT_FALSE(World::create(c, err));
  EXPECT_LT(heap.largest_allocation(), 32u * 1024 * 1024);
  EXPECT_NE(err.find("kestrel_truncated.pgm\": truncated pixel data (4000 x 4000 samples need at least 32000001 bytes"),
            std::string::npos)
      << err;
  std::remove(path.c_str());
}

TEST(SimTerrain, NoHeapInsideStepWithTerrainsMeasuredHeightsAndRotatingObstacles) {
  for (const std::string& terrain :
       {std::string("{type: heightfield, procedural: random_uniform, length_x_m: 12, width_y_m: 12, measure_heights: true}"),
        "{type: trimesh, mesh_file: " + kData + "slope_terrain.obj, origin_m: [0, 0, -1.5], measure_heights: true}"}) {
    WorldConfig c = scenario("env: {name: dynamic, num_envs: 4, terrain: " + terrain + "}\n"
                             "task: {name: position_setpoint, episode_len_env_steps: 60}\n");
    for (AssetClass& a : c.env.assets) a.max_angular_speed_rad_s = 2;
    c.robot.robots_per_env = 2;
    auto w = build(c);
    kestrel::test::HeapCounter counter;
    w->step(200);
    EXPECT_EQ(counter.allocations(), 0u) << terrain;
    EXPECT_GT(w->summary().resets, 0u) << terrain;
  }
}

TEST(SimTerrain, HashIdenticalFor1And3ThreadsOnTerrain) {
  std::uint64_t h[2];
  for (int k = 0; k < 2; ++k) {
    WorldConfig c = scenario("env: {name: forest, num_envs: 7, terrain: {type: heightfield, procedural: wave, length_x_m: 14, "
                             "width_y_m: 10, amplitude_m: 0.3, measure_heights: true}}\nseed: 3\n");
    c.num_threads = k == 0 ? 1 : 3;
    auto w = build(c);
    w->step(150);
    h[k] = w->state_hash();
  }
  EXPECT_EQ(h[0], h[1]);
}

// ---- issue 4 leftovers: mesh asset classes from YAML, rotating obstacles ------------------------

TEST(SimAssets, MeshAssetClassFromScenarioYaml) {
  WorldConfig c = scenario("env:\n  name: empty\n  num_envs: 2\n  assets:\n"
                           "    - {name: rocks, kind: mesh, mesh_file: " + kData + "rock.obj, num_assets: 3, semantic_id: 12,\n"
                           "       min_position_ratio: [0.5, 0.5, 0.5], max_position_ratio: [0.5, 0.5, 0.5]}\n"
                           "task: hover\n");
  ASSERT_EQ(c.env.assets.size(), 1u);
  EXPECT_EQ(c.env.assets[0].kind, AssetKind::mesh);
  EXPECT_EQ(c.env.assets[0].min_num_assets, 3);
  auto w = build(c);
  ASSERT_EQ(w->num_obstacles(0), 3);
  const Obstacle& o = w->obstacle(0, 0);
  EXPECT_EQ(o.shape.type, ShapeType::convex_hull);
  EXPECT_EQ(o.shape.num_vertices, 6);
  EXPECT_EQ(o.semantic_id, 12);
  // The hull collides: a sphere of r 0.2 at 0.6 m above the centre touches the top vertex (0.5 m)
  // 0.1 m deep.
  Shape s = sphere_at(o.shape.position_w + Vec3(0, 0, 0.6_r), 0.2_r);
  const Contact k = collide(s, o.shape);
  ASSERT_TRUE(k.hit);
  EXPECT_NEAR(k.depth_m, 0.1_r, 1e-3);
  EXPECT_NEAR(k.normal_w[2], 1, 1e-3);
  // Sensors see the mesh's own surface: a down-looking camera 0.1 m / 0.05 m off the top vertex
  // sees the octahedron face |x| + |y| + |z| = 0.5 at z = 0.35 above its centre.
  {
    WorldConfig cs = c;
    cs.env.num_envs = 1;
    SensorConfig cam;
    ASSERT_TRUE(registries().sensors.make("base_depth_camera", cam));
    cam.camera.mount = sensors::MountParams();
    cam.camera.mount.nominal_euler_deg = Vec3(0, 90, 0);
    cam.camera.noise.enable_sensor_noise = false;
    cam.camera.range.normalize_range = false;
    cam.camera.range.set_default_out_of_range_values();
    cs.robot.sensors.push_back(cam);
    auto ws = build(cs);
    const Vec3 centre_w = ws->obstacle(0, 0).shape.position_w;
    RigidBodyState& st = ws->robot_state(0, 0);
    st.position_w = centre_w + Vec3(0.1_r, 0.05_r, 1.5_r);
    st.orientation_wb = Quat::Identity();
    ws->render_sensors(0);
    const std::size_t px = static_cast<std::size_t>(ws->sensor_height(0) / 2) * static_cast<std::size_t>(ws->sensor_width(0)) +
                           static_cast<std::size_t>(ws->sensor_width(0) / 2);
    EXPECT_NEAR(ws->sensor_ranges(0, 0)[px], 1.5_r - 0.35_r, 5e-3);
    EXPECT_EQ(ws->sensor_segmentation(0, 0)[px], 12);
  }
  // Errors name the field and the allowed values.
  std::string err;
  EXPECT_FALSE(load_scenario_string("env: {name: empty, assets: [{name: r, kind: boulder}]}\n", "a.yaml", c, err));
  EXPECT_NE(err.find("a.yaml: env.assets.r.kind: expected one of tree, panel, cube"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("env: {name: empty, assets: [{name: r, kind: mesh}]}\n", "a.yaml", c, err));
  EXPECT_NE(err.find("env.assets.r.mesh_file: missing"), std::string::npos) << err;
  EXPECT_FALSE(load_scenario_string("env: {name: forest, assets: [{name: trees, kind: cube}]}\n", "a.yaml", c, err));
  EXPECT_NE(err.find("env.assets.trees: duplicate asset class name"), std::string::npos) << err;
  ASSERT_TRUE(load_scenario_string("env: {name: empty, assets: [{name: r, kind: mesh, mesh_file: nope.stl}]}\n", "a.yaml", c, err));
  EXPECT_FALSE(World::create(c, err));
  EXPECT_NE(err.find("env.assets.r: nope.stl: cannot open file"), std::string::npos) << err;
}

TEST(SimAssets, RotatingObstacleOrientationEqualsAnalyticRotation) {
  WorldConfig c = scenario("env:\n  name: empty\n  num_envs: 1\n  assets:\n"
                           "    - {name: spinner, kind: cube, num_assets: 1, max_angular_speed_rad_s: 3,\n"
                           "       min_position_ratio: [0.8, 0.8, 0.5], max_position_ratio: [0.8, 0.8, 0.5],\n"
                           "       max_euler_rad: [0.5, 0.5, 0.5]}\n"
                           "task: hover\n");
  auto w = build(c);
  w->set_auto_reset(false);
  ASSERT_EQ(w->num_obstacles(0), 1);
  const Obstacle o0 = w->obstacle(0, 0);
  ASSERT_GT(o0.angvel_w.norm(), 0.1);
  for (int k = 0; k < 3; ++k) EXPECT_LE(std::fabs(o0.angvel_w[k]), 3);
  const int n = 150;  // one physics step per env-step, dt 0.01 s
  w->step(n);
  const Vec3 rot = o0.angvel_w * (0.01_r * n);
  const Quat expect = (Quat(Eigen::AngleAxis<real>(rot.norm(), rot.normalized())) * o0.shape.orientation_wb).normalized();
  const Quat got = w->obstacle(0, 0).shape.orientation_wb;
  EXPECT_NEAR(std::fabs(got.dot(expect)), 1, 1e-5);
  EXPECT_NEAR(got.angularDistance(expect), 0, 2e-3);
  EXPECT_EQ(w->obstacle(0, 0).shape.position_w, o0.shape.position_w);  // no linear speed configured
}

TEST(SimAssets, ContactWithRotatingObstacleUsesItsSurfaceVelocity) {
  // A robot resting off-centre on a big disc spinning about +z is dragged along w x r by friction.
  WorldConfig c = scenario("env:\n  name: empty\n  num_envs: 1\n  collision_force_threshold: 1000\n  reset_on_collision: false\n"
                           "  assets:\n"
                           "    - {name: disc, kind: thin, num_assets: 1, min_size_m: [2, 0, 0.2], max_size_m: [2, 0, 0.2],\n"
                           "       min_position_ratio: [0.5, 0.5, 0.1], max_position_ratio: [0.5, 0.5, 0.1]}\n"
                           "controller: direct_motor_control\ntask: hover\n");
  auto w = build(c);
  w->set_auto_reset(false);
  motors_off(*w);
  Obstacle& d = w->obstacle(0, 0);
  d.angvel_w = Vec3(0, 0, 2);
  const Vec3 top = d.shape.position_w + Vec3(0, 0, d.shape.half_length_m);
  RigidBodyState& st = w->robot_state(0, 0);
  st = RigidBodyState();
  st.position_w = top + Vec3(1.0_r, 0, 0.2_r - 0.001_r);  // resting 1 mm deep at r = (1, 0, 0)
  w->step(1);
  const Vec3 f = w->contact_force_w(0, 0);
  EXPECT_GT(f[2], 0);
  // Surface velocity w x r = (0, 2, 0): friction pulls the robot towards +y.
  EXPECT_GT(f[1], 0.1 * std::fabs(f[0]) + 1e-4);
}
