// kestrel._core.Multibody's C++ side, shared by dynamics_py.cpp (the class) and
// robot_model_py.cpp (which hands out a Multibody built from a robot file).
#pragma once

#include "kestrel/dynamics/multibody.hpp"

namespace kestrel_py {

constexpr int kPyMaxBodies = 64;

struct PyMultibody {
  kestrel::dynamics::MultibodyModel<kPyMaxBodies> model;
  kestrel::dynamics::MultibodyData<kPyMaxBodies> data;
};

}  // namespace kestrel_py
