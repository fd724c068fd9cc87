// Upper bounds of the desktop harness's inputs, in one place (the README's "Limits" table lists
// them; every error message that enforces one names the field and the allowed range).
//
// Why bounds at all: each count below multiplies memory or work per step. Without one, a typo or
// a fuzzed file (robots_per_env: 2000000000, num_assets: 600000000, substeps: 2000000000, a
// 46341 x 46341 PGM header) ended in std::bad_alloc, signed overflow or a hang instead of a
// message naming the field. The values are far above anything the shipped scenarios use (1024
// environments, tens of obstacles, 1-2 robots per environment) and below int overflow in every
// product the set-up forms. Memory as a whole is bounded separately by an estimate made before
// anything is allocated (WorldConfig::max_memory_gib, World::estimate_bytes).
#pragma once

#include <cstdint>
#include <string>

namespace kestrel::sim {

struct WorldConfig;

// ---- scenario counts (env / robot / sim / threads) ---------------------------------------------
constexpr int kMaxNumEnvs = 1 << 20;               // env.num_envs, kestrel run --envs: 1,048,576
constexpr int kMaxRobotsPerEnv = 1024;             // robot.robots_per_env
constexpr int kMaxAssetsPerClass = 1 << 16;        // env.assets.<class>.num_assets: 65,536
// Obstacle slots of one environment: the sum over the classes of num_assets (a tree takes
// 1 + its branches). Keeps asset_class_slots() and its sum far from int overflow.
constexpr int kMaxObstacleSlotsPerEnv = 1 << 20;   // 1,048,576
constexpr int kMaxSubsteps = 1000;                 // sim.substeps (integrator sub-steps per physics step)
constexpr int kMaxPhysicsStepsPerEnvStep = 1000;   // env.num_physics_steps_per_env_step_mean (and _std)
constexpr int kMaxLatencyPhysicsSteps = 1000;      // env.max_latency_physics_steps
constexpr int kMaxThreads = 1024;                  // threads, kestrel run --threads
constexpr int kMaxSensorEveryEnvSteps = 1 << 20;   // sensors[].every
constexpr int kMaxSensorSide = 4096;               // sensors[].height, .width (pixels per side)
constexpr int kMaxNumWaves = 1000;                 // env.terrain.num_waves (work per height sample)
constexpr int kMaxMeasuredHeightPoints = 1 << 16;  // env.terrain.measured_points_x x _y, per robot
constexpr int kMaxAssetSemanticId = 32767;         // env.assets.<class>.semantic_id (stored in 16 bits)

// ---- files --------------------------------------------------------------------------------------
// Height-map samples (image width x height, or the procedural grid): 64 M (512 MiB of doubles
// while loading). Checked from the header, before any pixel buffer is allocated.
constexpr long long kMaxHeightmapSamples = 64ll * 1024 * 1024;
// Mesh vertex coordinates (OBJ/STL obstacles and trimesh terrain), metres, per component. Beyond
// it the collision (libccd MPR, whose loops have no iteration cap) and the float arithmetic of
// contact and rendering stop being meaningful; 1e6 m is 1000 km.
constexpr double kMaxMeshCoordinateM = 1e6;

// ---- memory -------------------------------------------------------------------------------------
// Default of WorldConfig::max_memory_gib (scenario `max_memory_gib`, kestrel run --max-memory-gib):
// the most a world's set-up may allocate, estimated before allocating.
constexpr double kDefaultMaxMemoryGiB = 4.0;
constexpr double kMaxMemoryGiBSetting = 1 << 20;   // upper end of the setting itself (1 PiB)

/// Checks every count of `config` against the bounds above (and the lower bounds that go with
/// them). On failure `error` names the field, the value and the allowed range, e.g.
/// "robot.robots_per_env: 2000000000 is out of range; allowed: 1..1024 (kMaxRobotsPerEnv)".
/// Used by every backend's set-up, so configs built in code (or changed by command-line flags
/// after loading) get the same checks as scenario files.
[[nodiscard]] bool check_config_limits(const WorldConfig& config, std::string& error);

/// "FIELD: VALUE is out of range; allowed: LO..HI (NAME)": the shared wording.
std::string out_of_range(const std::string& field, long long value, long long lo, long long hi, const char* name);

}  // namespace kestrel::sim
