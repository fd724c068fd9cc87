// Articulated-robot test set-ups shared by the backend, task, heap and golden-hash tests: every
// randomisation of simulator.* on (legged_gym's / LeggedGym-Ex's domain_rand ranges) and a small
// tiled terrain (legged_gym's curriculum tiles) with a narrow border.
#pragma once

#include "kestrel/sim/config.hpp"

namespace kestrel::test {

inline void randomise_all_articulated(sim::WorldConfig& c) {
  c.simulator.friction_min = 0.5_r;
  c.simulator.friction_max = 1.25_r;
  c.simulator.restitution_min = 0;
  c.simulator.restitution_max = 0.5_r;
  c.simulator.added_mass_min_kg = -1;
  c.simulator.added_mass_max_kg = 3;
  c.simulator.com_bias_max_m = 0.05_r;
  c.simulator.joint_armature_min_kg_m2 = 0.005_r;
  c.simulator.joint_armature_max_kg_m2 = 0.02_r;
  c.simulator.max_push_force_N = 30;
}

inline void tiled_terrain(sim::TerrainConfig& t, int rows, int cols, int max_init_level, real border_m = 2) {
  t.type = sim::TerrainType::heightfield;
  t.procedural = "curriculum";
  t.num_rows = rows;
  t.num_cols = cols;
  t.border_size_m = border_m;
  t.max_init_terrain_level = max_init_level;
}

}  // namespace kestrel::test
