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
// The functions mujoco_side.inc calls (and the version check's), named once: the pointers' types
// below and the dlsym lookups in make_mujoco_pypi.
#define KESTREL_MJ_FUNCTIONS(X)                                                                      \
  X(mj_loadXML) X(mj_deleteModel) X(mj_makeData) X(mj_deleteData) X(mj_copyData) X(mj_name2id)       \
  X(mj_resetDataKeyframe) X(mj_forward) X(mj_step) X(mj_contactForce) X(mj_getTotalmass)             \
  X(mj_versionString) X(mj_version)
struct Api {
#define KESTREL_MJ_POINTER(f) decltype(&::f) f = nullptr;
  KESTREL_MJ_FUNCTIONS(KESTREL_MJ_POINTER)
#undef KESTREL_MJ_POINTER
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
#define KESTREL_MJ_LOOKUP(f) get(g_api.f, #f);
    KESTREL_MJ_FUNCTIONS(KESTREL_MJ_LOOKUP)
#undef KESTREL_MJ_LOOKUP
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
