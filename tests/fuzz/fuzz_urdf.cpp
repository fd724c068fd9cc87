// Fuzz target: URDF text -> load_urdf, then apply_urdf into a one-environment world stepped 5 times.
// Contract: no crash or sanitizer report; a URDF that loads has a finite positive mass, finite
// positive principal moments and finite rotors (spin +-1); the world built from
// it (if World::create accepts it) keeps every state finite.
#include <cstdint>
#include <string>

#include "fuzz_common.hpp"
#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/urdf.hpp"
#include "kestrel/sim/world.hpp"

using namespace kestrel;
using namespace kestrel::sim;

namespace {
const WorldConfig& base_config() {
  static const WorldConfig cfg = [] {
    WorldConfig c;
    std::string err;
    const bool ok = load_scenario_string("env: {name: empty, num_envs: 1}\nrobot: base_quadrotor\n", "fuzz_urdf", c, err);
    KFUZZ_CHECK(ok, "base scenario: %s", err.c_str());
    c.num_threads = 1;
    return c;
  }();
  return cfg;
}
}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  (void)kfuzz::work_dir();
  (void)base_config();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = kfuzz::write_input("robot.urdf", data, size);
  UrdfRobot u;
  std::string err;
  if (!load_urdf(path, u, err)) return 0;
  KFUZZ_CHECK(std::isfinite(u.mass_kg) && u.mass_kg > 0, "mass %g", static_cast<double>(u.mass_kg));
  KFUZZ_CHECK(u.inertia_diag_kg_m2.allFinite() && (u.inertia_diag_kg_m2.array() > 0).all(), "inertia not finite/positive");
  KFUZZ_CHECK(u.rotors.size() == u.rotor_directions.size(), "rotors %zu, directions %zu", u.rotors.size(),
              u.rotor_directions.size());
  for (std::size_t i = 0; i < u.rotors.size(); ++i) {
    KFUZZ_CHECK(kfuzz::all_finite(u.rotors[i].position_b_m, 3) && kfuzz::all_finite(u.rotors[i].axis_b, 3), "rotor %zu not finite", i);
    KFUZZ_CHECK(u.rotor_directions[i] == 1 || u.rotor_directions[i] == -1, "rotor %zu direction %d", i,
                static_cast<int>(u.rotor_directions[i]));
  }
  WorldConfig cfg = base_config();
  if (!apply_urdf(path, cfg.robot, err)) return 0;
  std::unique_ptr<World> world = World::create(cfg, err);
  if (!world) return 0;
  for (int s = 0; s < 5; ++s) {
    world->step(1);
    const RigidBodyState& st = world->robot_state(0, 0);
    KFUZZ_CHECK(st.position_w.allFinite() && st.orientation_wb.coeffs().allFinite() && st.linvel_w.allFinite() &&
                    st.angvel_b.allFinite(),
                "state not finite after step %d", s);
  }
  (void)world->state_hash();
  return 0;
}
