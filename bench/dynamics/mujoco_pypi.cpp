// The PyPI wheel's libmujoco behind mujoco_runner.hpp, compiled against the wheel's own headers
// and loaded at run time (dlopen with RTLD_LOCAL | RTLD_DEEPBIND: its mj_* symbols resolve inside
// it, never to the Debian build the process links). Every function is called through a pointer
// from dlsym; decltype(&::f) names f's type without referring to the symbol.
#include <dlfcn.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <string>
#include <type_traits>

#include "mujoco_runner.hpp"

namespace {
struct Api {
  decltype(&::mj_loadXML) mj_loadXML = nullptr;
  decltype(&::mj_deleteModel) mj_deleteModel = nullptr;
  decltype(&::mj_makeData) mj_makeData = nullptr;
  decltype(&::mj_deleteData) mj_deleteData = nullptr;
  decltype(&::mj_copyData) mj_copyData = nullptr;
  decltype(&::mj_name2id) mj_name2id = nullptr;
  decltype(&::mj_resetDataKeyframe) mj_resetDataKeyframe = nullptr;
  decltype(&::mj_forward) mj_forward = nullptr;
  decltype(&::mj_step) mj_step = nullptr;
  decltype(&::mj_contactForce) mj_contactForce = nullptr;
  decltype(&::mj_getTotalmass) mj_getTotalmass = nullptr;
  decltype(&::mj_versionString) mj_versionString = nullptr;
  decltype(&::mj_version) mj_version = nullptr;
};
Api g_api;
}  // namespace

#define KESTREL_MJ(f) g_api.f
#if mjVERSION_HEADER >= 300
#define KESTREL_MJ_SOLVER_ITER(d) ((d)->solver_niter[0])
#else  // built against Debian's 2.x headers when the build found no wheel: never loaded then
#define KESTREL_MJ_SOLVER_ITER(d) ((d)->solver_iter)
#endif
#include "mujoco_side.inc"

namespace kestrel_bench {
std::unique_ptr<MujocoRunner> make_mujoco_pypi(const std::string& lib_path, std::string& err) {
  static void* handle = nullptr;
  if (handle == nullptr) {
    handle = dlopen(lib_path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND);
    if (handle == nullptr) {
      const char* e = dlerror();
      err = e != nullptr ? e : "dlopen failed";  // dlerror names the file
      return nullptr;
    }
    bool all = true;
    auto get = [&](auto& fn, const char* name) {
      fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(dlsym(handle, name));
      if (fn == nullptr) {
        err = std::string("no symbol ") + name;
        all = false;
      }
    };
    get(g_api.mj_loadXML, "mj_loadXML");
    get(g_api.mj_deleteModel, "mj_deleteModel");
    get(g_api.mj_makeData, "mj_makeData");
    get(g_api.mj_deleteData, "mj_deleteData");
    get(g_api.mj_copyData, "mj_copyData");
    get(g_api.mj_name2id, "mj_name2id");
    get(g_api.mj_resetDataKeyframe, "mj_resetDataKeyframe");
    get(g_api.mj_forward, "mj_forward");
    get(g_api.mj_step, "mj_step");
    get(g_api.mj_contactForce, "mj_contactForce");
    get(g_api.mj_getTotalmass, "mj_getTotalmass");
    get(g_api.mj_versionString, "mj_versionString");
    get(g_api.mj_version, "mj_version");
    if (!all) {
      dlclose(handle);
      handle = nullptr;
      return nullptr;
    }
    // The header this file was compiled against must be the library's (mjModel / mjData layouts).
    if (g_api.mj_version() != mjVERSION_HEADER) {
      err = std::string("MuJoCo ") + g_api.mj_versionString() + ", but the bench was compiled against the headers of " +
            std::to_string(mjVERSION_HEADER) + " (mjVERSION_HEADER)";
      dlclose(handle);
      handle = nullptr;
      return nullptr;
    }
  }
  return std::make_unique<MujocoSide>();
}
}  // namespace kestrel_bench
