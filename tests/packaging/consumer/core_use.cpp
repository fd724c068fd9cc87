// C++ module using the core headers directly.
#include <kestrel/allocation/presets.hpp>
#include <kestrel/controllers/lee.hpp>

extern "C" float consumer_quad_mass(void) { return static_cast<float>(kestrel::lee_params_base_quadrotor().mass_kg); }
extern "C" int consumer_quad_rotors(void) { return kestrel::allocation::kBaseQuadrotor.num_rotors; }
