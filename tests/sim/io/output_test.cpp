// Run outputs (sim/output.hpp): the CSVs the plots are drawn from (trajectory with targets and
// episodes, obstacles, bounds) and `kestrel run`'s progress line. The hand-drawn trajectory PNG and
// its line rasteriser are gone (issue 15: matplotlib draws the figures, python/kestrel/plots.py).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "kestrel/sim/output.hpp"
#include "kestrel/sim/registry.hpp"
#include "kestrel/sim/world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {
std::vector<std::vector<std::string>> read_csv(const std::string& path) {
  std::ifstream f(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(f, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cells.push_back(c);
    rows.push_back(cells);
  }
  return rows;
}
int column(const std::vector<std::string>& header, const std::string& name) {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<int>(i);
  ADD_FAILURE() << "no column " << name;
  return 0;
}
std::unique_ptr<World> forest_world(int envs, int episode_len) {
  WorldConfig c;
  EXPECT_TRUE(registries().envs.make("forest", c.env));
  c.env.num_envs = envs;
  c.num_threads = 1;
  c.seed = 42;
  c.task.episode_len_env_steps = episode_len;
  std::string err;
  auto w = World::create(c, err);
  EXPECT_TRUE(w) << err;
  return w;
}
}  // namespace

// trajectory.csv carries each point's target and episode: the target is the world's target of
// that episode, the episode number steps up exactly where the environment was reset.
TEST(SimOutput, TrajectoryCsvHasTargetsAndEpisodes) {
  auto w = forest_world(3, 40);
  ASSERT_TRUE(w);
  w->enable_trace(2, 100);
  const Vec3 first_target = w->target(0, 0);
  w->step(100);
  const std::string path = std::string(::testing::TempDir()) + "kestrel_trajectory_test.csv";
  std::string err;
  ASSERT_TRUE(write_trajectory_csv(*w, path, err)) << err;
  const auto rows = read_csv(path);
  std::remove(path.c_str());
  ASSERT_EQ(rows.size(), 1u + 2u * 100u);
  const auto& h = rows[0];
  EXPECT_EQ(h, (std::vector<std::string>{"env", "step", "x_m", "y_m", "z_m", "target_x_m", "target_y_m", "target_z_m", "episode"}));
  const int tx = column(h, "target_x_m"), ep = column(h, "episode"), x = column(h, "x_m");
  // Env 0, first point: episode 0, the target drawn at set-up; the last point's episode is the
  // number of resets the environment had before it (episodes of 40 env-steps: at least 2).
  EXPECT_EQ(rows[1][0], "0");
  EXPECT_EQ(rows[1][static_cast<std::size_t>(ep)], "0");
  EXPECT_NEAR(std::stod(rows[1][static_cast<std::size_t>(tx)]), static_cast<double>(first_target[0]), 1e-5);
  int last_episode = 0, changes = 0;
  for (std::size_t i = 2; i <= 100; ++i) {
    const int e = std::stoi(rows[i][static_cast<std::size_t>(ep)]);
    EXPECT_GE(e, last_episode);
    if (e != last_episode) {
      ++changes;
      // A new episode may bring a new target; within an episode the target never moves.
    } else {
      EXPECT_EQ(rows[i][static_cast<std::size_t>(tx)], rows[i - 1][static_cast<std::size_t>(tx)]) << i;
    }
    last_episode = e;
  }
  EXPECT_GE(changes, 2);
  EXPECT_EQ(static_cast<std::uint32_t>(last_episode), w->trace_episode(0, 99));
  EXPECT_LE(w->trace_episode(0, 99), w->stats(0).resets);
  // The point written is the traced position.
  EXPECT_NEAR(std::stod(rows[100][static_cast<std::size_t>(x)]), static_cast<double>(w->trace_point(0, 99)[0]), 1e-4);
}

// obstacles.csv: every obstacle of the first envs environments with its shape, pose and box, and
// envs.csv the bounds the plot frames them with.
TEST(SimOutput, ObstaclesAndBoundsCsv) {
  auto w = forest_world(4, 100);
  ASSERT_TRUE(w);
  w->step(2);
  std::string err;
  const std::string opath = std::string(::testing::TempDir()) + "kestrel_obstacles_test.csv";
  ASSERT_TRUE(write_obstacles_csv(*w, 2, opath, err)) << err;
  const auto rows = read_csv(opath);
  std::remove(opath.c_str());
  ASSERT_GT(w->num_obstacles(0), 0);
  ASSERT_EQ(rows.size(), 1u + static_cast<std::size_t>(w->num_obstacles(0) + w->num_obstacles(1)));
  const auto& h = rows[0];
  ASSERT_EQ(h.size(), 24u);
  const int shape = column(h, "shape"), cx = column(h, "x_m"), r = column(h, "radius_m"), lo = column(h, "aabb_min_x_m"),
            hi = column(h, "aabb_max_x_m"), kind = column(h, "kind");
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const int env = std::stoi(rows[i][0]), idx = std::stoi(rows[i][1]);
    ASSERT_LT(env, 2);
    const Obstacle& o = w->obstacle(env, idx);
    EXPECT_NEAR(std::stod(rows[i][static_cast<std::size_t>(cx)]), static_cast<double>(o.shape.position_w[0]), 1e-4);
    EXPECT_NEAR(std::stod(rows[i][static_cast<std::size_t>(r)]), static_cast<double>(o.shape.radius_m), 1e-5);
    EXPECT_NEAR(std::stod(rows[i][static_cast<std::size_t>(lo)]), static_cast<double>(o.aabb_min_w[0]), 1e-4);
    EXPECT_NEAR(std::stod(rows[i][static_cast<std::size_t>(hi)]), static_cast<double>(o.aabb_max_w[0]), 1e-4);
    const std::string s = rows[i][static_cast<std::size_t>(shape)];
    EXPECT_TRUE(s == "sphere" || s == "box" || s == "capsule" || s == "cylinder" || s == "convex_hull") << s;
    EXPECT_NE(rows[i][static_cast<std::size_t>(kind)], "unknown");
  }
  const std::string epath = std::string(::testing::TempDir()) + "kestrel_envs_test.csv";
  ASSERT_TRUE(write_env_csv(*w, epath, err)) << err;
  const auto env_rows = read_csv(epath);
  std::remove(epath.c_str());
  ASSERT_EQ(env_rows.size(), 5u);
  Vec3 lower, upper;
  w->lower_upper_bounds(3, lower, upper);
  EXPECT_NEAR(std::stod(env_rows[4][static_cast<std::size_t>(column(env_rows[0], "lower_x_m"))]), static_cast<double>(lower[0]), 1e-4);
  EXPECT_NEAR(std::stod(env_rows[4][static_cast<std::size_t>(column(env_rows[0], "upper_z_m"))]), static_cast<double>(upper[2]), 1e-4);
  EXPECT_FALSE(write_obstacles_csv(*w, 1, "/nonexistent-dir/obstacles.csv", err));
  EXPECT_NE(err.find("/nonexistent-dir/obstacles.csv"), std::string::npos) << err;
}

// The progress line's figures: done / total, percentage, rate and time left from the clock given.
TEST(SimOutput, ProgressLineText) {
  EXPECT_EQ(ProgressLine::format(512000, 1024000, 0.5), "  env-steps 512.0k / 1.02M (50%), 1.02M env-steps/s, 0.5 s left");
  EXPECT_EQ(ProgressLine::format(100, 1e9, 1.0), "  env-steps 100 / 1.00G (0%), 100 env-steps/s, 2777 h 46 min left");
  EXPECT_EQ(ProgressLine::format(3e6, 4e6, 10.0), "  env-steps 3.00M / 4.00M (75%), 300.0k env-steps/s, 3.3 s left");
  EXPECT_EQ(ProgressLine::format(1e6, 1e8, 10.0), "  env-steps 1.00M / 100.00M (1%), 100.0k env-steps/s, 16 min 30 s left");
  EXPECT_EQ(ProgressLine::format(0, 10, 0.0), "  env-steps 0 / 10 (0%), 0 env-steps/s, ? s left");
}

// The bench programs' unit (calls, steps, rays) in place of env-steps, same figures.
TEST(SimOutput, ProgressLineUnit) {
  EXPECT_EQ(ProgressLine::format(3e6, 4e6, 10.0, "calls"), "  calls 3.00M / 4.00M (75%), 300.0k calls/s, 3.3 s left");
  EXPECT_EQ(ProgressLine::format(3e6, 4e6, 10.0), ProgressLine::format(3e6, 4e6, 10.0, "env-steps"));
}

namespace {
std::string drain(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string s;
  char buf[512];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
  return s;
}
}  // namespace

// When it prints: not before kFirstAfterS, then at most every kIntervalS, and a complete final
// line with a newline; nothing at all when disabled or when the run ended before the first line.
TEST(SimOutput, ProgressLineTiming) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  ProgressLine p(f, true, 1000);
  p.update_at(100, 0.1);  // too early
  p.update_at(500, 0.6);  // first line
  p.update_at(550, 0.7);  // within the interval: skipped
  p.update_at(900, 0.9);  // printed
  p.finish_at(1.0);
  p.finish_at(1.1);  // once only
  EXPECT_EQ(p.lines(), 3);
  EXPECT_EQ(drain(f), "\r" + ProgressLine::format(500, 1000, 0.6) + "\033[K\r" + ProgressLine::format(900, 1000, 0.9) +
                          "\033[K\r" + ProgressLine::format(900, 1000, 1.0) + "\033[K\n");
  std::fclose(f);

  std::FILE* g = std::tmpfile();
  ProgressLine off(g, false, 1000);
  off.update_at(500, 2.0);
  off.finish_at(3.0);
  ProgressLine short_run(g, true, 1000);
  short_run.update_at(1000, 0.3);
  short_run.finish_at(0.3);
  EXPECT_EQ(off.lines() + short_run.lines(), 0);
  EXPECT_EQ(drain(g), "");
  std::fclose(g);
}

// clear() erases a shown line (a bench prints its row next) and only then; the next update draws
// it again; finish() after a clear still ends with the complete line.
TEST(SimOutput, ProgressLineClear) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  ProgressLine p(f, true, 100, "rays");
  p.clear();  // nothing shown yet: nothing written
  p.update_at(40, 0.6);
  p.clear();
  p.clear();  // once
  p.update_at(80, 0.9);
  p.finish_at(1.0);
  EXPECT_EQ(drain(f), "\r" + ProgressLine::format(40, 100, 0.6, "rays") + "\033[K\r\033[K\r" + ProgressLine::format(80, 100, 0.9, "rays") +
                          "\033[K\r" + ProgressLine::format(80, 100, 1.0, "rays") + "\033[K\n");
  std::fclose(f);
  std::FILE* g = std::tmpfile();
  ProgressLine off(g, false, 100);
  off.update_at(50, 1.0);
  off.clear();
  EXPECT_EQ(drain(g), "");
  std::fclose(g);
}
