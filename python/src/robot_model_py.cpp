// kestrel._core.load_robot_model: a robot file (MJCF or URDF, sim/articulated_robot.hpp) as the
// core's tree, for the oracle tests against MuJoCo and Pinocchio on the same file and for users:
// names, the tree's arrays (the Multibody constructor's, plus limits), the home pose, collision
// geoms and feet, and .multibody() for the core's rnea / crba / aba. Arrays are the core's real.
#include <cstdint>
#include <string>
#include <vector>

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "dynamics_py.hpp"
#include "kestrel/sim/articulated_robot.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using kestrel::real;
namespace dy = kestrel::dynamics;
namespace ks = kestrel::sim;

namespace {

// A new numpy array owning a copy (a property's default policy, reference_internal, would tie it to
// the robot, which an array with its own owner cannot be).
template <class T>
nb::object array_out(const std::vector<T>& v, const std::vector<std::size_t>& shape) {
  T* out = new T[v.size() > 0 ? v.size() : 1];
  for (std::size_t i = 0; i < v.size(); ++i) out[i] = v[i];
  nb::capsule owner(out, [](void* p) noexcept { delete[] static_cast<T*>(p); });
  return nb::cast(nb::ndarray<nb::numpy, T>(out, shape.size(), shape.data(), owner), nb::rv_policy::move);
}

// One array per body of a field of the tree: per(i, out) appends body i's numbers.
template <class T, class F>
nb::object per_body(const ks::ArticulatedRobot& r, std::initializer_list<std::size_t> tail, F per) {
  std::vector<T> v;
  const std::size_t n = static_cast<std::size_t>(r.multibody.num_bodies);
  for (std::size_t i = 0; i < n; ++i) per(static_cast<int>(i), v);
  std::vector<std::size_t> shape = {n};
  shape.insert(shape.end(), tail.begin(), tail.end());
  return array_out(v, shape);
}

const char* geom_type_name(ks::RobotGeomType t) {
  switch (t) {
    case ks::RobotGeomType::plane: return "plane";
    case ks::RobotGeomType::sphere: return "sphere";
    case ks::RobotGeomType::capsule: return "capsule";
    case ks::RobotGeomType::ellipsoid: return "ellipsoid";
    case ks::RobotGeomType::cylinder: return "cylinder";
    case ks::RobotGeomType::box: return "box";
    case ks::RobotGeomType::mesh: return "mesh";
  }
  return "?";
}

}  // namespace

void bind_robot_model(nb::module_& m) {
  using R = ks::ArticulatedRobot;
  nb::class_<R>(m, "RobotModel",
                "A robot file (MJCF or URDF) as the core's kinematic tree (sim/articulated_robot.hpp): bodies in "
                "MuJoCo's order, body 0 the base; the arrays are kestrel.Multibody's (parent, joint, axis, E_tree, "
                "r_tree, mass, com, inertia, gravity, armature, damping) plus limits, in the core's coordinates (free "
                "joint q [x y z qx qy qz qw], velocities [v; w] in the base frame).")
      .def_ro("path", &R::path)
      .def_ro("name", &R::name)
      .def_ro("body_names", &R::body_names)
      .def_ro("joint_names", &R::joint_names, "per body; '' for a fixed one")
      .def_ro("foot_bodies", &R::foot_bodies)
      .def_ro("foot_geoms", &R::foot_geoms, "per foot, the index into geoms of its sphere (-1: none)")
      .def_ro("total_mass", &R::total_mass_kg)
      .def_prop_ro("num_bodies", [](const R& r) { return r.multibody.num_bodies; })
      .def_prop_ro("num_dofs", [](const R& r) { return r.multibody.num_dofs; })
      .def_prop_ro("num_q", [](const R& r) { return r.multibody.num_q; })
      .def_prop_ro("home_q",
                   [](const R& r) -> nb::object {
                     if (!r.has_home) return nb::none();
                     return array_out(r.home_q, {r.home_q.size()});
                   },
                   "the keyframe 'home' in the core's coordinates, or None")
      .def_prop_ro("parent", [](const R& r) { return per_body<std::int32_t>(r, {}, [&](int i, auto& v) { v.push_back(r.multibody.parent[i]); }); })
      .def_prop_ro("joint", [](const R& r) {
        return per_body<std::int32_t>(r, {}, [&](int i, auto& v) { v.push_back(static_cast<std::int32_t>(r.multibody.joint[i])); });
      })
      .def_prop_ro("dof_index", [](const R& r) { return per_body<std::int32_t>(r, {}, [&](int i, auto& v) { v.push_back(r.multibody.dof_index[i]); }); })
      .def_prop_ro("q_index", [](const R& r) { return per_body<std::int32_t>(r, {}, [&](int i, auto& v) { v.push_back(r.multibody.q_index[i]); }); })
      .def_prop_ro("axis", [](const R& r) {
        return per_body<real>(r, {3}, [&](int i, auto& v) { for (int a = 0; a < 3; ++a) v.push_back(r.multibody.axis[i][a]); });
      })
      .def_prop_ro("E_tree", [](const R& r) {
        return per_body<real>(r, {3, 3}, [&](int i, auto& v) {
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) v.push_back(r.multibody.X_tree[i].E(a, b));
        });
      })
      .def_prop_ro("r_tree", [](const R& r) {
        return per_body<real>(r, {3}, [&](int i, auto& v) { for (int a = 0; a < 3; ++a) v.push_back(r.multibody.X_tree[i].r[a]); });
      })
      .def_prop_ro("mass", [](const R& r) { return per_body<real>(r, {}, [&](int i, auto& v) { v.push_back(r.multibody.body[i].mass); }); })
      .def_prop_ro("com", [](const R& r) {
        return per_body<real>(r, {3}, [&](int i, auto& v) { for (int a = 0; a < 3; ++a) v.push_back(r.multibody.body[i].com[a]); });
      })
      .def_prop_ro("inertia", [](const R& r) {
        return per_body<real>(r, {3, 3}, [&](int i, auto& v) {
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) v.push_back(r.multibody.body[i].inertia_com(a, b));
        });
      })
      .def_prop_ro("gravity", [](const R& r) {
        return array_out(std::vector<real>{r.multibody.gravity_w[0], r.multibody.gravity_w[1], r.multibody.gravity_w[2]}, {3});
      })
      .def_prop_ro("armature", [](const R& r) { return per_body<real>(r, {}, [&](int i, auto& v) { v.push_back(r.multibody.armature[i]); }); })
      .def_prop_ro("damping", [](const R& r) { return per_body<real>(r, {}, [&](int i, auto& v) { v.push_back(r.multibody.damping[i]); }); })
      .def_prop_ro("friction_loss", [](const R& r) { return per_body<real>(r, {}, [&](int i, auto& v) { v.push_back(r.multibody.friction_loss[i]); }); })
      .def_prop_ro("effort_limit", [](const R& r) { return per_body<real>(r, {}, [&](int i, auto& v) { v.push_back(r.multibody.effort_limit[i]); }); })
      .def_prop_ro("has_limit", [](const R& r) {
        return per_body<std::uint8_t>(r, {}, [&](int i, auto& v) { v.push_back(r.multibody.has_limit[i] ? 1 : 0); });
      })
      .def_prop_ro("q_min", [](const R& r) { return per_body<real>(r, {}, [&](int i, auto& v) { v.push_back(r.multibody.q_min[i]); }); })
      .def_prop_ro("q_max", [](const R& r) { return per_body<real>(r, {}, [&](int i, auto& v) { v.push_back(r.multibody.q_max[i]); }); })
      .def_prop_ro("geoms",
                   [](const R& r) {
                     nb::list out;
                     for (const ks::RobotGeom& g : r.geoms) {
                       nb::dict d;
                       d["name"] = g.name;
                       d["body"] = g.body;
                       d["type"] = geom_type_name(g.type);
                       d["size"] = nb::make_tuple(g.size[0], g.size[1], g.size[2]);
                       d["pos"] = nb::make_tuple(g.pos_b[0], g.pos_b[1], g.pos_b[2]);
                       d["quat_xyzw"] = nb::make_tuple(g.quat_xyzw_b[0], g.quat_xyzw_b[1], g.quat_xyzw_b[2], g.quat_xyzw_b[3]);
                       d["friction"] = g.friction;
                       out.append(d);
                     }
                     return out;
                   },
                   "collision primitives: name, body (-1: world), type, size (MuJoCo's), pose in the body frame, friction")
      .def(
          "multibody",
          [](const R& r) {
            kestrel_py::PyMultibody* p = new kestrel_py::PyMultibody();
            dy::MultibodyModel<kestrel_py::kPyMaxBodies>& d = p->model;
            const ks::RobotMultibody& s = r.multibody;
            d.num_bodies = s.num_bodies;
            for (int i = 0; i < s.num_bodies; ++i) {
              d.parent[i] = s.parent[i];
              d.joint[i] = s.joint[i];
              d.axis[i] = s.axis[i];
              d.X_tree[i] = s.X_tree[i];
              d.body[i] = s.body[i];
              d.armature[i] = s.armature[i];
              d.damping[i] = s.damping[i];
              d.has_limit[i] = s.has_limit[i];
              d.q_min[i] = s.q_min[i];
              d.q_max[i] = s.q_max[i];
              d.friction_loss[i] = s.friction_loss[i];
              d.effort_limit[i] = s.effort_limit[i];
            }
            d.gravity_w = s.gravity_w;
            if (dy::finish_model(d) != kestrel::Status::ok) {
              delete p;
              throw nb::value_error("multibody: the core refuses the tree");  // finished once already: not expected
            }
            return nb::cast(p, nb::rv_policy::take_ownership);
          },
          "A kestrel.Multibody of this tree (the core's rnea / crba / aba / point_jacobian).");

  m.def(
      "load_robot_model",
      [](const std::string& path) {
        ks::ArticulatedRobot r;
        std::string err;
        if (!ks::load_robot_model(path, r, err)) throw nb::value_error(err.c_str());
        return r;
      },
      "path"_a,
      "Loads an MJCF or URDF robot file (MuJoCo's compiler) as the core's tree; ValueError naming the file, the "
      "element and the problem otherwise.");
}
