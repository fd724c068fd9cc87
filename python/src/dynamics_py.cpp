// kestrel._core.Multibody: the core's articulated-body dynamics (dynamics/multibody.hpp: rnea,
// crba, aba) over a tree given as arrays, for the oracle tests against Pinocchio and for users
// who want the core's numbers from Python. Arrays are the core's real (float32 by default).
#include <cstdint>
#include <optional>
#include <string>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>

#include "dynamics_py.hpp"
#include "kestrel/dynamics/multibody.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using kestrel::real;
namespace dy = kestrel::dynamics;

namespace {

using kestrel_py::kPyMaxBodies;
using kestrel_py::PyMultibody;
using Arr = nb::ndarray<const real, nb::c_contig, nb::device::cpu>;
using Ints = nb::ndarray<const std::int32_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

void need(bool ok, const std::string& what) {
  if (!ok) throw nb::value_error(what.c_str());
}

void need_shape(const Arr& a, std::initializer_list<std::size_t> shape, const char* name) {
  bool ok = a.ndim() == shape.size();
  std::size_t k = 0;
  for (std::size_t s : shape) ok = ok && a.shape(k++) == s;
  std::string want = "(";
  k = 0;
  for (std::size_t s : shape) want += (k++ ? ", " : "") + std::to_string(s);
  need(ok, std::string(name) + ": expected shape " + want + (shape.size() == 1 ? ",)" : ")") + " of the core's real type");
}

nb::ndarray<nb::numpy, real, nb::ndim<1>> vector_out(const real* v, std::size_t n) {
  real* out = new real[n];
  for (std::size_t i = 0; i < n; ++i) out[i] = v[i];
  nb::capsule owner(out, [](void* p) noexcept { delete[] static_cast<real*>(p); });
  return nb::ndarray<nb::numpy, real, nb::ndim<1>>(out, {n}, owner);
}

}  // namespace

void bind_dynamics(nb::module_& m) {
  nb::class_<PyMultibody>(m, "Multibody",
                          "A kinematic tree on a fixed or floating base (dynamics/multibody.hpp): body i hangs from parent[i] "
                          "(-1: the world) by joint[i] (0 revolute, 1 prismatic, 2 fixed, 3 free: body 0 only, the floating "
                          "base, Pinocchio's free flyer: q [x y z qx qy qz qw], velocities [v; w] in the base frame) along "
                          "axis[i] (joint frame); "
                          "the joint frame is (E_tree[i], r_tree[i]) in the parent's (Featherstone's Plücker transform: E "
                          "rotates parent coordinates into joint coordinates, r is the joint origin in the parent frame); "
                          "body i's mass, centre of mass and inertia about it in its own frame.")
      .def(
          "__init__",
          [](PyMultibody* self, Ints parent, Ints joint, Arr axis, Arr E_tree, Arr r_tree, Arr mass, Arr com, Arr inertia,
             Arr gravity, std::optional<Arr> armature, std::optional<Arr> damping) {
            const std::size_t n = parent.shape(0);
            need(n >= 1 && n <= static_cast<std::size_t>(kPyMaxBodies),
                 "parent: expected 1 to " + std::to_string(kPyMaxBodies) + " bodies");
            need(joint.shape(0) == n, "joint: expected one joint type per body");
            need_shape(axis, {n, 3}, "axis");
            need_shape(E_tree, {n, 3, 3}, "E_tree");
            need_shape(r_tree, {n, 3}, "r_tree");
            need_shape(mass, {n}, "mass");
            need_shape(com, {n, 3}, "com");
            need_shape(inertia, {n, 3, 3}, "inertia");
            need_shape(gravity, {3}, "gravity");
            if (armature) need_shape(*armature, {n}, "armature");
            if (damping) need_shape(*damping, {n}, "damping");
            new (self) PyMultibody();
            dy::MultibodyModel<kPyMaxBodies>& md = self->model;
            md.num_bodies = static_cast<int>(n);
            for (std::size_t i = 0; i < n; ++i) {
              md.parent[i] = parent.data()[i];
              md.joint[i] = static_cast<dy::JointType>(joint.data()[i]);
              for (int a = 0; a < 3; ++a) {
                md.axis[i][a] = axis.data()[3 * i + a];
                md.X_tree[i].r[a] = r_tree.data()[3 * i + a];
                md.body[i].com[a] = com.data()[3 * i + a];
                for (int b = 0; b < 3; ++b) {
                  md.X_tree[i].E(a, b) = E_tree.data()[9 * i + 3 * a + b];
                  md.body[i].inertia_com(a, b) = inertia.data()[9 * i + 3 * a + b];
                }
              }
              md.body[i].mass = mass.data()[i];
              if (armature) md.armature[i] = armature->data()[i];
              if (damping) md.damping[i] = damping->data()[i];
            }
            md.gravity_w = kestrel::Vec3(gravity.data()[0], gravity.data()[1], gravity.data()[2]);
            need(dy::finish_model(md) == kestrel::Status::ok,
                 "Multibody: invalid tree (expected parent[i] in [-1, i), joint 0/1/2, or 3 for body 0 from the world "
                 "without armature or damping, unit axes, positive masses, finite symmetric inertias with a positive "
                 "diagonal)");
          },
          "parent"_a, "joint"_a, "axis"_a, "E_tree"_a, "r_tree"_a, "mass"_a, "com"_a, "inertia"_a, "gravity"_a,
          "armature"_a = nb::none(), "damping"_a = nb::none())
      .def_prop_ro("num_dofs", [](const PyMultibody& s) { return s.model.num_dofs; }, "velocity coordinates (nv)")
      .def_prop_ro("num_q", [](const PyMultibody& s) { return s.model.num_q; }, "configuration coordinates (nq)")
      .def(
          "rnea",
          [](PyMultibody& s, Arr q, Arr qd, Arr qdd) {
            const std::size_t n = static_cast<std::size_t>(s.model.num_dofs);
            need_shape(q, {static_cast<std::size_t>(s.model.num_q)}, "q");
            need_shape(qd, {n}, "qd");
            need_shape(qdd, {n}, "qdd");
            real tau[dy::max_dofs<kPyMaxBodies>()] = {};
            dy::rnea(s.model, s.data, q.data(), qd.data(), qdd.data(), tau);
            return vector_out(tau, n);
          },
          "q"_a, "qd"_a, "qdd"_a, "Inverse dynamics (RNEA): the joint forces for the accelerations qdd at (q, qd).")
      .def(
          "aba",
          [](PyMultibody& s, Arr q, Arr qd, Arr tau) {
            const std::size_t n = static_cast<std::size_t>(s.model.num_dofs);
            need_shape(q, {static_cast<std::size_t>(s.model.num_q)}, "q");
            need_shape(qd, {n}, "qd");
            need_shape(tau, {n}, "tau");
            real qdd[dy::max_dofs<kPyMaxBodies>()] = {};
            need(dy::aba(s.model, s.data, q.data(), qd.data(), tau.data(), qdd) == kestrel::Status::ok,
                 "q/qd/tau: non-finite values or a base quaternion off unit length (the core refuses them)");
            return vector_out(qdd, n);
          },
          "q"_a, "qd"_a, "tau"_a, "Forward dynamics (ABA): the accelerations under the joint forces tau at (q, qd).")
      .def(
          "crba",
          [](PyMultibody& s, Arr q) {
            const std::size_t n = static_cast<std::size_t>(s.model.num_dofs);
            need_shape(q, {static_cast<std::size_t>(s.model.num_q)}, "q");
            real* H = new real[n * n];
            dy::crba(s.model, s.data, q.data(), H, static_cast<int>(n));
            nb::capsule owner(H, [](void* p) noexcept { delete[] static_cast<real*>(p); });
            return nb::ndarray<nb::numpy, real, nb::ndim<2>>(H, {n, n}, owner);
          },
          "q"_a, "The joint-space mass matrix (CRBA).")
      .def(
          "point_jacobian",
          [](PyMultibody& s, Arr q, int body, Arr point) {
            const std::size_t n = static_cast<std::size_t>(s.model.num_dofs);
            need_shape(q, {static_cast<std::size_t>(s.model.num_q)}, "q");
            need_shape(point, {3}, "point");
            need(body >= 0 && body < s.model.num_bodies, "body: expected an index in [0, " + std::to_string(s.model.num_bodies) + ")");
            dy::Transform X_world[kPyMaxBodies];
            dy::forward_kinematics(s.model, s.data, q.data(), X_world);
            real* J = new real[6 * n];
            dy::point_jacobian(s.model, X_world, body, kestrel::Vec3(point.data()[0], point.data()[1], point.data()[2]), J,
                               static_cast<int>(n));
            nb::capsule owner(J, [](void* p) noexcept { delete[] static_cast<real*>(p); });
            return nb::ndarray<nb::numpy, real, nb::ndim<2>>(J, {6, n}, owner);
          },
          "q"_a, "body"_a, "point"_a,
          "The Jacobian (6, num_dofs) of a point fixed on a body (body frame): rows linear velocity of the point, "
          "angular velocity of the body, in world coordinates.");
}
