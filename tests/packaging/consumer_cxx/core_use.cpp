// C++ module using the core headers directly (Eigen comes in through them).
#include <kestrel/allocation/presets.hpp>
#include <kestrel/controllers/lee.hpp>

float consumer_quad_mass() { return static_cast<float>(kestrel::lee_params_base_quadrotor().mass_kg); }
int consumer_quad_rotors() { return kestrel::allocation::kBaseQuadrotor.num_rotors; }
