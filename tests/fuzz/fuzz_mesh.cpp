// Fuzz target: an OBJ or STL file (byte 0 picks: even .obj, odd .STL; the rest is the file) ->
// load_mesh, SceneMesh::build, a trimesh Terrain (height_at, sphere/box collide), and a
// one-environment world with the mesh as a rotating obstacle class, stepped 3 times.
// Contract: no crash, no sanitizer report, no hang; a mesh that loads has finite vertices (within
// sim/limits.hpp's coordinate bound) and in-range indices; terrain probes and robot states finite.
#include <cstdint>
#include <string>

#include "fuzz_common.hpp"
#include "kestrel/sim/limits.hpp"
#include "kestrel/sim/mesh.hpp"
#include "kestrel/sim/scenario.hpp"
#include "kestrel/sim/world.hpp"
#include "terrain_checks.hpp"

using namespace kestrel;
using namespace kestrel::sim;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  (void)kfuzz::work_dir();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string path = kfuzz::write_input((data[0] & 1) ? "mesh.STL" : "mesh.obj", data + 1, size - 1);
  TriangleMesh m;
  std::string err;
  if (!load_mesh(path, m, err)) return 0;
  KFUZZ_CHECK(!m.triangles.empty(), "a loaded mesh has no triangles");
  for (const Vec3& v : m.vertices)
    KFUZZ_CHECK(v.allFinite() && v.cwiseAbs().maxCoeff() <= static_cast<real>(kMaxMeshCoordinateM), "vertex out of range");
  const int nv = static_cast<int>(m.vertices.size());
  for (const auto& t : m.triangles)
    for (int i : t) KFUZZ_CHECK(i >= 0 && i < nv, "index %d of %d vertices", i, nv);
  SceneMesh scene;
  (void)scene.build(m, Vec3(0.5_r, -0.25_r, 0));

  TerrainConfig tc;
  tc.type = TerrainType::trimesh;
  tc.mesh_file = path;
  std::unique_ptr<Terrain> terrain;
  if (Terrain::build(tc, 1, terrain, err)) kfuzz::probe_terrain(*terrain, data[0]);

  WorldConfig cfg;
  if (!load_scenario_string("env: {name: empty, num_envs: 1}\nrobot: base_quadrotor\n", "fuzz_mesh", cfg, err)) return 0;
  cfg.num_threads = 1;
  AssetClass a;
  a.name = "m";
  a.kind = AssetKind::mesh;
  a.mesh_file = path;
  a.num_assets = a.min_num_assets = 2;
  a.max_angular_speed_rad_s = 1;
  cfg.env.assets.push_back(a);
  std::unique_ptr<World> world = World::create(cfg, err);
  if (!world) return 0;
  for (int s = 0; s < 3; ++s) {
    world->step(1);
    const RigidBodyState& st = world->robot_state(0, 0);
    KFUZZ_CHECK(st.position_w.allFinite() && st.orientation_wb.coeffs().allFinite() && st.linvel_w.allFinite() &&
                    st.angvel_b.allFinite(),
                "state not finite after step %d", s);
  }
  return 0;
}
