// Debian's libmujoco (linked) behind mujoco_runner.hpp.
#include <mujoco/mujoco.h>

#include <algorithm>

#include "mujoco_runner.hpp"

#define KESTREL_MJ(f) ::f
#define KESTREL_MJ_SOLVER_ITER(d) ((d)->solver_iter)
#include "mujoco_side.inc"

namespace kestrel_bench {
std::unique_ptr<MujocoRunner> make_mujoco_debian() { return std::make_unique<MujocoSide>(); }
}  // namespace kestrel_bench
