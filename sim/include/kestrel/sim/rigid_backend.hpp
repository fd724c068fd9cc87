// The rigid backend's own object, for code that needs more than the Simulator interface carries
// (tests of the World, tools that render its ray sensors). Kept out of simulator.hpp so that the
// interface names no backend.
#pragma once

#include "kestrel/sim/simulator.hpp"
#include "kestrel/sim/world.hpp"

namespace kestrel::sim {

/// The World behind a rigid Simulator; nullptr for any other backend.
World* rigid_world(Simulator& sim);
const World* rigid_world(const Simulator& sim);

}  // namespace kestrel::sim
