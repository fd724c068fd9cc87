// One MuJoCo build's side of bench_legged_step.cpp: a robot file with a floor, the joint PD toward
// the `home` keyframe each step, mj_step. Two builds run side by side in one process: Debian's
// libmujoco (the version the sim library's loader links, mujoco_debian.cpp) and the one from PyPI
// that the issue names (`mujoco` in python/requirements.txt; its wheel ships libmujoco.so and the
// headers: mujoco_pypi.cpp loads the library with dlopen(RTLD_LOCAL | RTLD_DEEPBIND), so its
// symbols never meet the other build's). Both compile mujoco_side.inc against their own headers.
#pragma once

#include <memory>
#include <string>

namespace kestrel_bench {

class MujocoRunner {
 public:
  virtual ~MujocoRunner() = default;
  // menagerie_cone: the MuJoCo Menagerie Go2's solver settings (elliptic cone, impratio 100)
  // instead of the file's own (MuJoCo's defaults). False with err set when it cannot load.
  virtual bool init(const std::string& robot_path, bool menagerie_cone, double kp, double kd, double dt_s, std::string& err) = 0;
  virtual void step() = 0;   // the PD into ctrl, then mj_step
  virtual void save() = 0;   // keep the current state (mj_copyData)
  virtual void restore() = 0;  // back to the state save() kept
  virtual double x() const = 0;
  virtual double y() const = 0;
  virtual double z() const = 0;
  virtual double normal_force() const = 0;  // summed over the active contacts (N)
  virtual int contacts() const = 0;         // d->ncon
  virtual int rows() const = 0;             // d->nefc
  virtual int solver_iterations() const = 0;
  virtual double total_mass() const = 0;
  virtual std::string describe() const = 0;  // the solver settings, one line
  virtual std::string version() const = 0;   // mj_versionString()
};

// Debian's libmujoco, linked.
std::unique_ptr<MujocoRunner> make_mujoco_debian();
// The PyPI wheel's library at lib_path; nullptr (err: why, without the path) when it cannot be loaded.
std::unique_ptr<MujocoRunner> make_mujoco_pypi(const std::string& lib_path, std::string& err);

}  // namespace kestrel_bench
