// The whole allocation layer in one include: airframes and presets, the pseudo-inverse, the three
// allocators (plain pseudo-inverse, sequential desaturation, constrained least squares) and the
// motor model. See each header for its method and sources.
#pragma once

#include "kestrel/allocation/airframe.hpp"
#include "kestrel/allocation/allocation_model.hpp"
#include "kestrel/allocation/cls_allocator.hpp"
#include "kestrel/allocation/motor_model.hpp"
#include "kestrel/allocation/pinv.hpp"
#include "kestrel/allocation/presets.hpp"
#include "kestrel/allocation/sequential_desaturation.hpp"
