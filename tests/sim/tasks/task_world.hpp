// Tests of tasks on the rigid backend reach the World behind the task's Simulator (to place a
// robot, read the World's episode counter or its obstacles) through rigid_backend.hpp, as any
// tool that needs more than the Simulator interface does.
#pragma once

#include "kestrel/sim/rigid_backend.hpp"
#include "kestrel/sim/task.hpp"

inline kestrel::sim::World& world_of(kestrel::sim::Task& t) { return *kestrel::sim::rigid_world(t.simulator()); }
inline const kestrel::sim::World& world_of(const kestrel::sim::Task& t) { return *kestrel::sim::rigid_world(t.simulator()); }
