// URDF robot files (see urdf.hpp). Geometry is composed in double precision and rounded to real
// once at the end.
#include "kestrel/sim/urdf.hpp"

#include <tinyxml2.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>

namespace kestrel::sim {

namespace {

using V3 = Eigen::Vector3d;
using M3 = Eigen::Matrix3d;

struct UrdfError {
  std::string msg;
};

[[noreturn]] void bad(const std::string& where, const std::string& msg) { throw UrdfError{where + ": " + msg}; }

double parse_number(const char* text, const std::string& where) {
  if (text == nullptr) bad(where, "missing");
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  while (end && *end != 0 && std::isspace(static_cast<unsigned char>(*end))) ++end;
  if (end == text || (end && *end != 0) || !std::isfinite(v)) bad(where, std::string("expected a finite number, got \"") + text + "\"");
  return v;
}

V3 parse_vec3(const char* text, const std::string& where) {
  if (text == nullptr) bad(where, "missing");
  std::istringstream in(text);
  V3 v;
  std::string rest;
  if (!(in >> v[0] >> v[1] >> v[2]) || (in >> rest) || !v.allFinite())
    bad(where, std::string("expected three finite numbers \"x y z\", got \"") + text + "\"");
  return v;
}

struct Pose {
  V3 p = V3::Zero();
  M3 r = M3::Identity();
};

/// <origin xyz rpy> (absent: identity). URDF rpy: fixed-axis roll about x, then pitch about y,
/// then yaw about z, i.e. R = Rz(yaw) Ry(pitch) Rx(roll).
Pose parse_origin(const tinyxml2::XMLElement* parent, const std::string& where) {
  Pose o;
  const tinyxml2::XMLElement* e = parent ? parent->FirstChildElement("origin") : nullptr;
  if (e == nullptr) return o;
  if (e->Attribute("xyz")) o.p = parse_vec3(e->Attribute("xyz"), where + "/origin@xyz");
  if (e->Attribute("rpy")) {
    const V3 rpy = parse_vec3(e->Attribute("rpy"), where + "/origin@rpy");
    o.r = (Eigen::AngleAxisd(rpy[2], V3::UnitZ()) * Eigen::AngleAxisd(rpy[1], V3::UnitY()) * Eigen::AngleAxisd(rpy[0], V3::UnitX()))
              .toRotationMatrix();
  }
  return o;
}

struct Link {
  const tinyxml2::XMLElement* xml = nullptr;
  std::string parent_joint;  // empty for the root
  Pose in_base;              // link frame in the base frame
  bool placed = false;
};
struct Joint {
  const tinyxml2::XMLElement* xml = nullptr;
  std::string type, parent, child;
  Pose origin;
};

/// rotor_<N> / prop_<N> -> N, else -1.
int rotor_index(const std::string& name) {
  for (const char* prefix : {"rotor_", "prop_"}) {
    const std::string pre(prefix);
    if (name.size() <= pre.size() || name.compare(0, pre.size(), pre) != 0) continue;
    const std::string digits = name.substr(pre.size());
    if (digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 3) return -1;
    return std::atoi(digits.c_str());
  }
  return -1;
}

/// The kinematic tree as the file gives it: links and joints by name, the one root link.
struct Tree {
  std::map<std::string, Link> links;
  std::map<std::string, Joint> joints;
  std::string base;
};

/// Links, joints and the root of <robot>: names unique, every joint between known links, each link
/// the child of at most one joint, exactly one root.
Tree read_tree(const tinyxml2::XMLElement* robot) {
  Tree t;
  std::map<std::string, Link>& links = t.links;
  std::map<std::string, Joint>& joints = t.joints;
  for (const tinyxml2::XMLElement* l = robot->FirstChildElement("link"); l; l = l->NextSiblingElement("link")) {
    const char* n = l->Attribute("name");
    if (n == nullptr || *n == 0) bad("link", "a <link> without a name");
    if (links.count(n) != 0) bad(std::string("link[") + n + "]", "duplicate link name");
    links[n].xml = l;
  }
  if (links.empty()) bad("robot", "no <link> elements");
  for (const tinyxml2::XMLElement* j = robot->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
    const char* n = j->Attribute("name");
    if (n == nullptr || *n == 0) bad("joint", "a <joint> without a name");
    const std::string w = std::string("joint[") + n + "]";
    if (joints.count(n) != 0) bad(w, "duplicate joint name");
    Joint jt;
    jt.xml = j;
    jt.type = j->Attribute("type") ? j->Attribute("type") : "";
    const tinyxml2::XMLElement* pe = j->FirstChildElement("parent");
    const tinyxml2::XMLElement* ce = j->FirstChildElement("child");
    if (pe == nullptr || pe->Attribute("link") == nullptr) bad(w + "/parent@link", "missing");
    if (ce == nullptr || ce->Attribute("link") == nullptr) bad(w + "/child@link", "missing");
    jt.parent = pe->Attribute("link");
    jt.child = ce->Attribute("link");
    if (links.count(jt.parent) == 0) bad(w + "/parent@link", "unknown link \"" + jt.parent + "\"");
    if (links.count(jt.child) == 0) bad(w + "/child@link", "unknown link \"" + jt.child + "\"");
    if (!links[jt.child].parent_joint.empty()) bad(w + "/child@link", "link \"" + jt.child + "\" is the child of two joints");
    links[jt.child].parent_joint = n;
    jt.origin = parse_origin(j, w);
    joints[n] = jt;
  }
  std::string& base = t.base;
  for (const auto& kv : links) {
    if (!kv.second.parent_joint.empty()) continue;
    if (!base.empty()) bad("robot", "two root links (\"" + base + "\" and \"" + kv.first + "\"); expected one base link");
    base = kv.first;
  }
  if (base.empty()) bad("robot", "no root link (the joints form a loop)");
  return t;
}

/// Every link's pose in the base frame: walk up to a placed ancestor (the link count bounds the walk).
void place_links(Tree& t) {
  std::map<std::string, Link>& links = t.links;
  std::map<std::string, Joint>& joints = t.joints;
  links[t.base].placed = true;
  for (auto& kv : links) {
    std::vector<std::string> chain;
    std::string cur = kv.first;
    while (!links[cur].placed) {
      chain.push_back(cur);
      if (chain.size() > links.size()) bad("robot", "the joints form a loop");
      cur = joints[links[cur].parent_joint].parent;
    }
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      Link& l = links[*it];
      const Joint& j = joints[l.parent_joint];
      const Pose& p = links[j.parent].in_base;
      l.in_base.p = p.p + p.r * j.origin.p;
      l.in_base.r = p.r * j.origin.r;
      l.placed = true;
    }
  }
}

/// Composite mass, centre of mass (returned, base frame) and inertia about the centre of mass; the
/// body axes must be principal axes (Kestrel's rigid body takes a diagonal inertia).
V3 composite_inertia(const Tree& t, UrdfRobot& out) {
  const std::string& base = t.base;
  double mass = 0;
  V3 moment = V3::Zero();
  struct Part {
    double m;
    V3 c;
    M3 i;
  };
  std::vector<Part> parts;
  for (const auto& kv : t.links) {
    const std::string w = "link[" + kv.first + "]/inertial";
    const tinyxml2::XMLElement* in = kv.second.xml->FirstChildElement("inertial");
    if (in == nullptr) continue;
    const tinyxml2::XMLElement* me = in->FirstChildElement("mass");
    if (me == nullptr) bad(w + "/mass", "missing");
    const double m = parse_number(me->Attribute("value"), w + "/mass@value");
    if (m < 0) bad(w + "/mass@value", "expected a number >= 0");
    const Pose o = parse_origin(in, w);
    M3 il = M3::Zero();
    if (const tinyxml2::XMLElement* ie = in->FirstChildElement("inertia")) {
      const char* names[6] = {"ixx", "iyy", "izz", "ixy", "ixz", "iyz"};
      double v[6];
      for (int k = 0; k < 6; ++k) v[k] = parse_number(ie->Attribute(names[k]), w + "/inertia@" + names[k]);
      il << v[0], v[3], v[4], v[3], v[1], v[5], v[4], v[5], v[2];
    } else if (m > 0) {
      bad(w + "/inertia", "missing (a link with mass needs ixx, iyy, izz, ixy, ixz, iyz)");
    }
    const Pose& lb = kv.second.in_base;
    const M3 r = lb.r * o.r;
    parts.push_back(Part{m, lb.p + lb.r * o.p, r * il * r.transpose()});
    mass += m;
    moment += m * parts.back().c;
  }
  if (!(mass > 0)) bad("link[" + base + "]/inertial/mass", "the robot has no mass (expected a positive <mass value>)");
  // The body frame is the composite centre of mass (Kestrel's rigid body turns about it): the
  // rotors are re-expressed relative to it (read_rotors) and the inertia is taken about it below.
  const V3 com = moment / mass;
  out.com_offset_m = Vec3(static_cast<real>(com[0]), static_cast<real>(com[1]), static_cast<real>(com[2]));
  M3 inertia = M3::Zero();
  for (const Part& p : parts) {
    const V3 d = p.c - com;
    inertia += p.i + p.m * (d.squaredNorm() * M3::Identity() - d * d.transpose());
  }
  const double imax = inertia.diagonal().maxCoeff();
  if (!(inertia.diagonal().minCoeff() > 0)) bad("link[" + base + "]/inertial/inertia", "expected positive moments ixx, iyy, izz");
  if (std::fabs(inertia(0, 1)) > 1e-6 * imax || std::fabs(inertia(0, 2)) > 1e-6 * imax || std::fabs(inertia(1, 2)) > 1e-6 * imax)
    bad("link[" + base + "]/inertial/inertia",
        "products of inertia (ixy, ixz, iyz of the composite body) must be zero: Kestrel takes a diagonal inertia in "
        "principal axes; align the base frame with them");
  out.mass_kg = static_cast<real>(mass);
  out.inertia_diag_kg_m2 = Vec3(static_cast<real>(inertia(0, 0)), static_cast<real>(inertia(1, 1)), static_cast<real>(inertia(2, 2)));
  return com;
}

/// The base link's collision shape (box, sphere or cylinder centred on the body frame), if any.
void base_shape(const Tree& tree, UrdfRobot& out) {
  const std::string& base = tree.base;
  if (const tinyxml2::XMLElement* col = tree.links.at(base).xml->FirstChildElement("collision")) {
    const std::string w = "link[" + base + "]/collision";
    const Pose o = parse_origin(col, w);
    if (o.p.norm() > 1e-9 || !o.r.isIdentity(1e-9)) bad(w + "/origin", "expected a zero origin (the shape is centred on the body frame)");
    const tinyxml2::XMLElement* g = col->FirstChildElement("geometry");
    const tinyxml2::XMLElement* shape = g ? g->FirstChildElement() : nullptr;
    if (shape == nullptr) bad(w + "/geometry", "missing (expected box, sphere or cylinder)");
    const std::string t = shape->Name();
    ShapeSpec s;
    if (t == "box") {
      const V3 size = parse_vec3(shape->Attribute("size"), w + "/geometry/box@size");
      if (!(size.minCoeff() > 0)) bad(w + "/geometry/box@size", "expected three positive numbers");
      s.type = ShapeType::box;
      s.half_extents_m = Vec3(static_cast<real>(size[0] / 2), static_cast<real>(size[1] / 2), static_cast<real>(size[2] / 2));
    } else if (t == "sphere") {
      s.type = ShapeType::sphere;
      s.radius_m = static_cast<real>(parse_number(shape->Attribute("radius"), w + "/geometry/sphere@radius"));
      if (!(s.radius_m > 0)) bad(w + "/geometry/sphere@radius", "expected a positive number");
    } else if (t == "cylinder") {
      s.type = ShapeType::cylinder;
      s.radius_m = static_cast<real>(parse_number(shape->Attribute("radius"), w + "/geometry/cylinder@radius"));
      s.half_length_m = static_cast<real>(parse_number(shape->Attribute("length"), w + "/geometry/cylinder@length") / 2);
      if (!(s.radius_m > 0) || !(s.half_length_m > 0)) bad(w + "/geometry/cylinder", "expected positive radius and length");
    } else {
      bad(w + "/geometry/" + t, "unsupported geometry; allowed: box, sphere, cylinder");
    }
    out.has_shape = true;
    out.shape = s;
  }
}

/// Rotor links rotor_<N> / prop_<N>, numbered 0, 1, ... : position relative to the centre of mass
/// `com` and thrust axis (base axes), spin direction from their joint's axis.
void read_rotors(const Tree& t, const V3& com, UrdfRobot& out) {
  std::map<int, std::string> rotor_links;
  for (const auto& kv : t.links) {
    const int n = rotor_index(kv.first);
    if (n < 0) continue;
    if (rotor_links.count(n) != 0) bad("link[" + kv.first + "]", "rotor " + std::to_string(n) + " is also link \"" + rotor_links[n] + "\"");
    rotor_links[n] = kv.first;
  }
  if (static_cast<int>(rotor_links.size()) > allocation::kMaxRotors)
    bad("robot", "more than " + std::to_string(allocation::kMaxRotors) + " rotor links");
  int expect = 0;
  for (const auto& kv : rotor_links) {
    const std::string w = "link[" + kv.second + "]";
    if (kv.first != expect) bad(w, "rotor links must be numbered 0, 1, ... without gaps (missing rotor_" + std::to_string(expect) + ")");
    ++expect;
    if (kv.second == t.base) bad(w, "the base link cannot be a rotor");
    const Link& l = t.links.at(kv.second);
    const Joint& j = t.joints.at(l.parent_joint);
    const std::string jw = "joint[" + l.parent_joint + "]";
    if (j.type != "continuous" && j.type != "revolute")
      bad(jw + "@type", "a rotor's joint must be continuous or revolute (its axis gives the spin direction), got \"" + j.type + "\"");
    const tinyxml2::XMLElement* ax = j.xml->FirstChildElement("axis");
    if (ax == nullptr) bad(jw + "/axis", "missing (expected xyz=\"0 0 1\" or \"0 0 -1\")");
    V3 a = parse_vec3(ax->Attribute("xyz"), jw + "/axis@xyz");
    if (!(a.norm() > 0)) bad(jw + "/axis@xyz", "zero axis");
    a.normalize();
    if (std::fabs(a[2]) < 1 - 1e-6) bad(jw + "/axis@xyz", "expected 0 0 1 or 0 0 -1 (the rotor link's z axis is its thrust axis)");
    allocation::RotorSpec r{};
    const V3 axis = l.in_base.r.col(2);
    const V3 hub = l.in_base.p - com;  // relative to the centre of mass (the body frame)
    for (int k = 0; k < 3; ++k) {
      r.position_b_m[k] = static_cast<real>(hub[k]);
      r.axis_b[k] = static_cast<real>(axis[k]);
    }
    out.rotors.push_back(r);
    out.rotor_directions.push_back(static_cast<std::int8_t>(a[2] > 0 ? 1 : -1));
  }
}

UrdfRobot parse(const tinyxml2::XMLDocument& doc) {
  const tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  if (robot == nullptr) bad("robot", "missing the <robot> root element");
  UrdfRobot out;
  out.name = robot->Attribute("name") ? robot->Attribute("name") : "";
  Tree t = read_tree(robot);
  out.base_link = t.base;
  place_links(t);
  const V3 com = composite_inertia(t, out);
  base_shape(t, out);
  read_rotors(t, com, out);
  return out;
}

}  // namespace

bool load_urdf(const std::string& path, UrdfRobot& out, std::string& error) {
  tinyxml2::XMLDocument doc;
  const tinyxml2::XMLError e = doc.LoadFile(path.c_str());
  if (e == tinyxml2::XML_ERROR_FILE_NOT_FOUND || e == tinyxml2::XML_ERROR_FILE_COULD_NOT_BE_OPENED) {
    error = path + ": cannot open file";
    return false;
  }
  if (e != tinyxml2::XML_SUCCESS) {
    error = path + ": not well-formed XML (" + std::string(doc.ErrorStr() ? doc.ErrorStr() : "parse error") + ")";
    return false;
  }
  try {
    out = parse(doc);
    return true;
  } catch (const UrdfError& u) {
    error = path + ": " + u.msg;
  }
  return false;
}

bool apply_urdf(const std::string& path, RobotConfig& robot, std::string& error, std::string* urdf_name) {
  UrdfRobot u;
  if (!load_urdf(path, u, error)) return false;
  if (urdf_name != nullptr) *urdf_name = u.name;
  robot.mass_kg = u.mass_kg;
  robot.inertia_diag_kg_m2 = u.inertia_diag_kg_m2;
  if (u.has_shape) robot.shape = u.shape;
  if (!u.rotors.empty()) {
    robot.rotors = u.rotors;
    robot.rotor_directions = u.rotor_directions;
  }
  return true;
}

}  // namespace kestrel::sim
