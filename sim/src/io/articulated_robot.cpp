// Robot files through MuJoCo's compiler into the core's MultibodyModel (see articulated_robot.hpp).
// Everything is composed in double, as MuJoCo keeps it, and rounded to real once when stored.
#include "kestrel/sim/articulated_robot.hpp"

#include <mujoco/mujoco.h>
#include <tinyxml2.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>

#include "kestrel/kernel/quaternion.hpp"

namespace kestrel::sim {

namespace {

using V3 = Eigen::Vector3d;
using M3 = Eigen::Matrix3d;

struct LoadError {
  std::string msg;
};

[[noreturn]] void bad(const std::string& where, const std::string& msg) { throw LoadError{where + ": " + msg}; }

// MuJoCo's quaternion (w x y z): the rotation child -> parent.
M3 rotation_wxyz(const mjtNum* q) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string name_of(const mjModel* m, int type, int id) {
  const char* n = mj_id2name(m, type, id);
  return n != nullptr ? std::string(n) : std::string();
}

std::string body_element(const mjModel* m, int b) {
  const std::string n = name_of(m, mjOBJ_BODY, b);
  return n.empty() ? "body #" + std::to_string(b) : "body \"" + n + "\"";
}

std::string joint_element(const mjModel* m, int j) {
  const std::string n = name_of(m, mjOBJ_JOINT, j);
  return n.empty() ? "joint #" + std::to_string(j) + " (in " + body_element(m, m->jnt_bodyid[j]) + ")" : "joint \"" + n + "\"";
}

// A collision mesh's points (RobotGeom::points): the vertices of its convex hull (MuJoCo's
// compiler computes it, qhull, into mesh_graph: numvert, numface, then vert_edgeadr[numvert] and
// vert_globalid[numvert]), all of them if the file's mesh has no hull; above
// kMaxMeshCollisionPoints, the hull's extreme vertices along kMaxMeshCollisionPoints directions
// spread over the sphere (a Fibonacci lattice), which keeps its outline against the ground. In the
// geom's frame: MuJoCo stores mesh vertices in the frame geom_pos / geom_quat place.
std::vector<Vec3> mesh_collision_points(const mjModel* m, int mesh) {
  std::vector<Vec3> all;
  const int adr = m->mesh_vertadr[mesh], nv = m->mesh_vertnum[mesh];
  auto vertex = [&](int k) {
    const float* v = m->mesh_vert + 3 * (adr + k);
    return Vec3(static_cast<real>(v[0]), static_cast<real>(v[1]), static_cast<real>(v[2]));
  };
  const int gadr = m->mesh_graphadr[mesh];
  if (gadr >= 0) {
    const int* graph = m->mesh_graph + gadr;
    const int hull_n = graph[0];
    for (int k = 0; k < hull_n; ++k) all.push_back(vertex(graph[2 + hull_n + k]));
  } else {
    for (int k = 0; k < nv; ++k) all.push_back(vertex(k));
  }
  if (static_cast<int>(all.size()) <= kMaxMeshCollisionPoints) return all;
  std::vector<Vec3> picked;
  std::vector<bool> taken(all.size(), false);
  const double golden = 3.14159265358979323846 * (3.0 - std::sqrt(5.0));
  for (int d = 0; d < kMaxMeshCollisionPoints; ++d) {
    const double z = 1 - 2 * (d + 0.5) / kMaxMeshCollisionPoints, rho = std::sqrt(1 - z * z), phi = golden * d;
    const Vec3 dir(static_cast<real>(rho * std::cos(phi)), static_cast<real>(rho * std::sin(phi)), static_cast<real>(z));
    std::size_t best = 0;
    for (std::size_t k = 1; k < all.size(); ++k)
      if (all[k].dot(dir) > all[best].dot(dir)) best = k;
    if (!taken[best]) {
      taken[best] = true;
      picked.push_back(all[best]);
    }
  }
  return picked;
}

std::string geom_element(const mjModel* m, int g) {
  const std::string n = name_of(m, mjOBJ_GEOM, g);
  return (n.empty() ? "geom #" + std::to_string(g) : "geom \"" + n + "\"") + " (in " + body_element(m, m->geom_bodyid[g]) + ")";
}

// A symmetric range's half-width; an asymmetric one is refused (the core's effort limit is one number).
double symmetric_limit(double lo, double hi, const std::string& where) {
  if (std::fabs(lo + hi) > 1e-9 * std::max(1.0, std::fabs(hi - lo)))
    bad(where, "an asymmetric range [" + num(lo) + ", " + num(hi) +
                   "] (the core's effort limit is symmetric, one number per joint)");
  return std::fabs(hi);
}

// URDF <joint name><limit effort> by joint name: MuJoCo 2.2 does not carry URDF effort limits.
std::map<std::string, double> urdf_efforts(const std::string& path) {
  std::map<std::string, double> out;
  tinyxml2::XMLDocument doc;
  if (doc.LoadFile(path.c_str()) != tinyxml2::XML_SUCCESS) return out;  // MuJoCo has read it already
  const tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  if (robot == nullptr) return out;  // MJCF
  for (const tinyxml2::XMLElement* j = robot->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
    const tinyxml2::XMLElement* lim = j->FirstChildElement("limit");
    double e = 0;
    if (j->Attribute("name") && lim && lim->QueryDoubleAttribute("effort", &e) == tinyxml2::XML_SUCCESS) {
      if (!std::isfinite(e) || e < 0)
        bad("joint \"" + std::string(j->Attribute("name")) + "\"/limit@effort", "expected a finite effort >= 0");
      out[j->Attribute("name")] = e;
    }
  }
  return out;
}

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};

// mj_loadXML keeps the last model it compiled in a global (for mj_saveLastXML) in MuJoCo 2.2: one
// load at a time.
std::mutex& load_mutex() {
  static std::mutex m;
  return m;
}

void convert(const mjModel* m, const std::string& path, ArticulatedRobot& r) {
  if (m->ntendon > 0) bad("tendon", "tendons are not supported (the core's trees have none)");
  if (m->neq > 0) bad("equality", "equality constraints are not supported (the core's trees are open chains)");
  if (m->nmocap > 0) bad("mocap body", "mocap bodies are not supported");
  r.name = m->names != nullptr ? std::string(m->names) : std::string();  // the model name comes first in names
  // MuJoCo body -> core body (-1: world or welded to it); the frame shift of a body to its joint.
  std::vector<int> core_of(static_cast<std::size_t>(m->nbody), -1);
  std::vector<V3> shift(static_cast<std::size_t>(m->nbody), V3::Zero());
  // Pose of world-welded bodies in the world (for their geoms and children).
  std::vector<M3> R_world(static_cast<std::size_t>(m->nbody), M3::Identity());
  std::vector<V3> p_world(static_cast<std::size_t>(m->nbody), V3::Zero());
  RobotMultibody& mb = r.multibody;
  mb = RobotMultibody();
  int n = 0;
  for (int b = 1; b < m->nbody; ++b) {
    const int pb = m->body_parentid[b];
    const std::string where = body_element(m, b);
    const int nj = m->body_jntnum[b];
    if (nj > 1) bad(where, std::to_string(nj) + " joints; the core takes one joint per body (split the body)");
    const M3 R_pb = rotation_wxyz(m->body_quat + 4 * b);
    const V3 p_pb(m->body_pos[3 * b], m->body_pos[3 * b + 1], m->body_pos[3 * b + 2]);
    if (nj == 0 && core_of[static_cast<std::size_t>(pb)] < 0) {  // welded to the world: part of it
      R_world[static_cast<std::size_t>(b)] = R_world[static_cast<std::size_t>(pb)] * R_pb;
      p_world[static_cast<std::size_t>(b)] = p_world[static_cast<std::size_t>(pb)] + R_world[static_cast<std::size_t>(pb)] * p_pb;
      continue;
    }
    if (n >= kMaxRobotBodies)
      bad(where, "more than " + std::to_string(kMaxRobotBodies) + " moving bodies (kMaxRobotBodies)");
    const int i = n++;
    core_of[static_cast<std::size_t>(b)] = i;
    const int p = core_of[static_cast<std::size_t>(pb)];
    mb.parent[i] = p;
    r.body_names.push_back(name_of(m, mjOBJ_BODY, b));
    std::string jname;
    dynamics::JointType type = dynamics::JointType::fixed;
    V3 axis = V3::UnitX();
    if (nj == 1) {
      const int j = m->body_jntadr[b];
      jname = name_of(m, mjOBJ_JOINT, j);
      const std::string jwhere = joint_element(m, j);
      switch (m->jnt_type[j]) {
        case mjJNT_FREE:
          if (i != 0 || pb != 0)
            bad(jwhere, "a free joint only on the first body, directly under the world (the core's floating base)");
          type = dynamics::JointType::free;
          break;
        case mjJNT_BALL: bad(jwhere, "ball joints are not supported (the core has revolute, prismatic, fixed and free joints)");
        case mjJNT_HINGE: type = dynamics::JointType::revolute; break;
        case mjJNT_SLIDE: type = dynamics::JointType::prismatic; break;
        default: bad(jwhere, "unknown joint type " + std::to_string(m->jnt_type[j]));
      }
      axis = V3(m->jnt_axis[3 * j], m->jnt_axis[3 * j + 1], m->jnt_axis[3 * j + 2]);
      if (type != dynamics::JointType::free) shift[static_cast<std::size_t>(b)] = V3(m->jnt_pos[3 * j], m->jnt_pos[3 * j + 1], m->jnt_pos[3 * j + 2]);
      const int d = m->jnt_dofadr[j];
      if (type == dynamics::JointType::free) {
        if (m->dof_armature[d] != 0 || m->dof_damping[d] != 0 || m->dof_frictionloss[d] != 0)
          bad(jwhere, "armature, damping or frictionloss on the free joint (the core's floating base takes none)");
      } else {
        mb.armature[i] = static_cast<real>(m->dof_armature[d]);
        mb.damping[i] = static_cast<real>(m->dof_damping[d]);
        mb.friction_loss[i] = static_cast<real>(m->dof_frictionloss[d]);
        if (m->jnt_limited[j]) {
          mb.has_limit[i] = true;
          mb.q_min[i] = static_cast<real>(m->jnt_range[2 * j]);
          mb.q_max[i] = static_cast<real>(m->jnt_range[2 * j + 1]);
        }
      }
    }
    r.joint_names.push_back(jname);
    mb.joint[i] = type;
    mb.axis[i] = axis.cast<real>();
    // X_tree: the parent's (shifted) frame -> this body's joint frame. A free body's is the
    // identity: MuJoCo's free-joint position is the base's world pose, not relative to body_pos.
    if (type == dynamics::JointType::free) {
      mb.X_tree[i] = dynamics::Transform();
    } else {
      M3 R = R_pb;
      V3 o = p_pb + R_pb * shift[static_cast<std::size_t>(b)];
      if (p < 0) {  // under the world or a world-welded body
        o = p_world[static_cast<std::size_t>(pb)] + R_world[static_cast<std::size_t>(pb)] * o;
        R = R_world[static_cast<std::size_t>(pb)] * R;
      } else {
        o -= shift[static_cast<std::size_t>(pb)];
      }
      mb.X_tree[i].E = R.transpose().cast<real>();
      mb.X_tree[i].r = o.cast<real>();
    }
    // Inertia in the (shifted) body frame.
    const double mass = m->body_mass[b];
    if (!(mass > 0)) bad(where, "mass " + num(mass) + " kg; the core needs a positive mass on every body");
    const M3 Ri = rotation_wxyz(m->body_iquat + 4 * b);
    const V3 d(m->body_inertia[3 * b], m->body_inertia[3 * b + 1], m->body_inertia[3 * b + 2]);
    if (!(d.minCoeff() > 0)) bad(where, "a principal moment of inertia <= 0; the core needs positive ones");
    const M3 I = Ri * d.asDiagonal() * Ri.transpose();
    mb.body[i].mass = static_cast<real>(mass);
    mb.body[i].com = (V3(m->body_ipos[3 * b], m->body_ipos[3 * b + 1], m->body_ipos[3 * b + 2]) - shift[static_cast<std::size_t>(b)]).cast<real>();
    mb.body[i].inertia_com = (0.5 * (I + I.transpose())).cast<real>();
    r.total_mass_kg += static_cast<real>(mass);
  }
  if (n == 0) bad("worldbody", "no moving body (every body is welded to the world)");
  mb.num_bodies = n;
  mb.gravity_w = V3(m->opt.gravity[0], m->opt.gravity[1], m->opt.gravity[2]).cast<real>();

  // Effort limits: actuators first, then URDF <limit effort>.
  std::vector<bool> effort_set(static_cast<std::size_t>(n), false);
  for (int a = 0; a < m->nu; ++a) {
    if (m->actuator_trntype[a] != mjTRN_JOINT) continue;
    const int j = m->actuator_trnid[2 * a];
    const int i = core_of[static_cast<std::size_t>(m->jnt_bodyid[j])];
    const std::string an = name_of(m, mjOBJ_ACTUATOR, a);
    const std::string where = an.empty() ? "actuator #" + std::to_string(a) : "actuator \"" + an + "\"";
    if (i < 0 || mb.joint[i] == dynamics::JointType::free) bad(where, "drives the free joint; the core's joints drives are one-dof");
    const double gear = std::fabs(m->actuator_gear[6 * a]);
    double limit = -1;
    if (m->actuator_forcelimited[a]) {
      limit = gear * symmetric_limit(m->actuator_forcerange[2 * a], m->actuator_forcerange[2 * a + 1], where + "@forcerange");
    } else if (m->actuator_ctrllimited[a] && m->actuator_dyntype[a] == mjDYN_NONE && m->actuator_gaintype[a] == mjGAIN_FIXED &&
               m->actuator_biastype[a] == mjBIAS_NONE) {  // a motor: force = gain x ctrl
      limit = gear * std::fabs(m->actuator_gainprm[mjNGAIN * a]) *
              symmetric_limit(m->actuator_ctrlrange[2 * a], m->actuator_ctrlrange[2 * a + 1], where + "@ctrlrange");
    }
    if (limit < 0) continue;  // no bound on the joint force
    if (effort_set[static_cast<std::size_t>(i)])
      bad(where, "a second actuator on " + joint_element(m, j) + " (the core takes one effort limit per joint)");
    effort_set[static_cast<std::size_t>(i)] = true;
    mb.effort_limit[i] = static_cast<real>(limit);
  }
  const std::map<std::string, double> efforts = urdf_efforts(path);
  for (int i = 0; i < n; ++i)
    if (!effort_set[static_cast<std::size_t>(i)] && !r.joint_names[static_cast<std::size_t>(i)].empty()) {
      const auto it = efforts.find(r.joint_names[static_cast<std::size_t>(i)]);
      if (it != efforts.end() && mb.joint[i] != dynamics::JointType::free) mb.effort_limit[i] = static_cast<real>(it->second);
    }

  if (dynamics::finish_model(mb) != Status::ok)
    bad("the tree", "the core refuses it (dynamics::finish_model: parents before children, unit axes, positive masses, "
                    "finite symmetric inertias with a positive diagonal, limits with q_min <= q_max)");

  // Collision geometry.
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_contype[g] == 0 && m->geom_conaffinity[g] == 0) continue;  // visual only
    RobotGeom geom;
    switch (m->geom_type[g]) {
      case mjGEOM_PLANE: geom.type = RobotGeomType::plane; break;
      case mjGEOM_SPHERE: geom.type = RobotGeomType::sphere; break;
      case mjGEOM_CAPSULE: geom.type = RobotGeomType::capsule; break;
      case mjGEOM_ELLIPSOID: geom.type = RobotGeomType::ellipsoid; break;
      case mjGEOM_CYLINDER: geom.type = RobotGeomType::cylinder; break;
      case mjGEOM_BOX: geom.type = RobotGeomType::box; break;
      case mjGEOM_MESH: geom.type = RobotGeomType::mesh; break;
      case mjGEOM_HFIELD: bad(geom_element(m, g), "height-field collision is not supported on a robot");
      default: bad(geom_element(m, g), "geom type " + std::to_string(m->geom_type[g]) + " is not supported");
    }
    const int b = m->geom_bodyid[g];
    geom.name = name_of(m, mjOBJ_GEOM, g);
    geom.body = core_of[static_cast<std::size_t>(b)];
    V3 pos(m->geom_pos[3 * g], m->geom_pos[3 * g + 1], m->geom_pos[3 * g + 2]);
    Eigen::Quaterniond q(m->geom_quat[4 * g], m->geom_quat[4 * g + 1], m->geom_quat[4 * g + 2], m->geom_quat[4 * g + 3]);
    if (geom.body < 0) {  // a world geom: its pose in the world
      pos = p_world[static_cast<std::size_t>(b)] + R_world[static_cast<std::size_t>(b)] * pos;
      q = Eigen::Quaterniond(R_world[static_cast<std::size_t>(b)]) * q;
    } else {
      pos -= shift[static_cast<std::size_t>(b)];
    }
    q.normalize();
    geom.size = V3(m->geom_size[3 * g], m->geom_size[3 * g + 1], m->geom_size[3 * g + 2]).cast<real>();
    geom.pos_b = pos.cast<real>();
    geom.quat_xyzw_b = Vec4(static_cast<real>(q.x()), static_cast<real>(q.y()), static_cast<real>(q.z()), static_cast<real>(q.w()));
    geom.friction = static_cast<real>(m->geom_friction[3 * g]);
    geom.contype = m->geom_contype[g];
    geom.conaffinity = m->geom_conaffinity[g];
    if (geom.type == RobotGeomType::mesh) geom.points = mesh_collision_points(m, m->geom_dataid[g]);
    r.geoms.push_back(geom);
  }

  // Feet: by body name, then by geom name.
  std::vector<bool> is_foot(static_cast<std::size_t>(n), false);
  for (int i = 0; i < n; ++i)
    if (lower(r.body_names[static_cast<std::size_t>(i)]).find("foot") != std::string::npos) is_foot[static_cast<std::size_t>(i)] = true;
  for (const RobotGeom& g : r.geoms)
    if (g.body >= 0 && lower(g.name).find("foot") != std::string::npos) is_foot[static_cast<std::size_t>(g.body)] = true;
  for (int i = 0; i < n; ++i) {
    if (!is_foot[static_cast<std::size_t>(i)]) continue;
    r.foot_bodies.push_back(i);
    int fg = -1;
    for (std::size_t k = 0; k < r.geoms.size() && fg < 0; ++k)
      if (r.geoms[k].body == i && r.geoms[k].type == RobotGeomType::sphere) fg = static_cast<int>(k);
    r.foot_geoms.push_back(fg);
  }

  // The "home" keyframe in the core's coordinates.
  for (int k = 0; k < m->nkey; ++k) {
    if (name_of(m, mjOBJ_KEY, k) != "home") continue;
    const mjtNum* qpos = m->key_qpos + static_cast<std::ptrdiff_t>(m->nq) * k;
    r.home_q.assign(static_cast<std::size_t>(mb.num_q), real(0));
    for (int b = 1; b < m->nbody; ++b) {
      const int i = core_of[static_cast<std::size_t>(b)];
      if (i < 0 || m->body_jntnum[b] != 1) continue;
      const int a = m->jnt_qposadr[m->body_jntadr[b]], c = mb.q_index[i];
      if (mb.joint[i] == dynamics::JointType::free) {
        for (int t = 0; t < 3; ++t) r.home_q[static_cast<std::size_t>(c + t)] = static_cast<real>(qpos[a + t]);
        for (int t = 0; t < 3; ++t) r.home_q[static_cast<std::size_t>(c + 3 + t)] = static_cast<real>(qpos[a + 4 + t]);  // x y z
        r.home_q[static_cast<std::size_t>(c + 6)] = static_cast<real>(qpos[a + 3]);                                      // w
      } else {
        r.home_q[static_cast<std::size_t>(c)] = static_cast<real>(qpos[a]);
      }
    }
    r.has_home = true;
    break;
  }
  r.path = path;
}

}  // namespace

bool load_robot_model(const std::string& path, ArticulatedRobot& out, std::string& error) {
  if (!std::ifstream(path).good()) {
    error = path + ": cannot open file";
    return false;
  }
  std::unique_ptr<mjModel, ModelDeleter> model;
  {
    std::lock_guard<std::mutex> lock(load_mutex());
    char msg[1024] = "";
    model.reset(mj_loadXML(path.c_str(), nullptr, msg, sizeof msg));
    if (!model) {
      // MuJoCo's message names the element and the line ("Error: ... Element 'x', line N").
      std::string text(msg);
      while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
      for (char& ch : text)
        if (ch == '\n') ch = ' ';  // one line: "Error: <problem> Element '<x>', line N" 
      error = path + ": " + (text.empty() ? std::string("MuJoCo could not load it") : text);
      return false;
    }
  }
  ArticulatedRobot robot;
  try {
    convert(model.get(), path, robot);
  } catch (const LoadError& e) {
    error = path + ": " + e.msg;
    return false;
  }
  out = std::move(robot);
  return true;
}

int find_body(const ArticulatedRobot& robot, const std::string& name) {
  for (std::size_t i = 0; i < robot.body_names.size(); ++i)
    if (robot.body_names[i] == name) return static_cast<int>(i);
  return -1;
}

bool to_collision_shape(const RobotGeom& g, dynamics::CollisionShape& s) {
  s.body = g.body;
  s.p_b = g.pos_b;
  s.R_b = rotation_matrix(quat_from_xyzw(g.quat_xyzw_b));
  s.friction = g.friction;
  switch (g.type) {
    case RobotGeomType::sphere:
      s.type = dynamics::ShapeType::sphere;
      s.size = Vec3(g.size[0], 0, 0);
      return true;
    case RobotGeomType::capsule:
    case RobotGeomType::cylinder:
      s.type = dynamics::ShapeType::capsule;
      s.size = Vec3(g.size[0], g.size[1], 0);
      return true;
    case RobotGeomType::box:
    case RobotGeomType::ellipsoid:
      s.type = dynamics::ShapeType::box;
      s.size = g.size;
      return true;
    case RobotGeomType::mesh:
      s.type = dynamics::ShapeType::convex;
      s.points = g.points.data();
      s.num_points = static_cast<int>(g.points.size());
      return s.num_points > 0;
    case RobotGeomType::plane:
      return false;
  }
  return false;
}

std::string models_dir() {
  const char* env = std::getenv("KESTREL_MODELS_DIR");
  if (env != nullptr && env[0] != '\0') return env;
  return KESTREL_MODELS_DIR_DEFAULT;
}

}  // namespace kestrel::sim
