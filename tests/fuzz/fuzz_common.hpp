// Shared helpers of the libFuzzer harnesses (tests/fuzz/): contract checks that abort (so the
// fuzzer records the input as a crash), and a private temporary directory holding links to the
// repository's data files (tests/sim/data), where a scenario's relative urdf:, mesh_file: and
// image_file: resolve, and where inputs that must be files (URDF, meshes, height maps) are written.
#pragma once

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#define KFUZZ_CHECK(cond, ...)                                                       \
  do {                                                                               \
    if (!(cond)) {                                                                   \
      std::fprintf(stderr, "fuzz contract broken at %s:%d: %s: ", __FILE__, __LINE__, #cond); \
      std::fprintf(stderr, __VA_ARGS__);                                             \
      std::fprintf(stderr, "\n");                                                    \
      std::abort();                                                                  \
    }                                                                                \
  } while (0)

namespace kfuzz {

template <class T>
bool all_finite(const T* p, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(p[i])) return false;
  return true;
}

/// The harness's working directory: links to every file of tests/sim/data, at the top and under
/// data/ (tests/sim/*.yaml name data/FILE). Removed at exit.
inline const std::string& work_dir() {
  static const std::string dir = [] {
    namespace fs = std::filesystem;
    // KESTREL_FUZZ_WORK_DIR (the regression runs set it): a fixed path, so that paths compared
    // inside the code under test, and hence the fuzzer's choices, do not depend on the pid.
    const char* env = std::getenv("KESTREL_FUZZ_WORK_DIR");
    const fs::path d = env != nullptr && env[0] != '\0' ? fs::path(env)
                                                        : fs::temp_directory_path() / ("kestrel_fuzz_" + std::to_string(::getpid()));
    fs::create_directories(d / "data");
    for (const auto& e : fs::directory_iterator(KESTREL_FUZZ_DATA_DIR)) {
      std::error_code ec;
      fs::create_symlink(e.path(), d / e.path().filename(), ec);
      fs::create_symlink(e.path(), d / "data" / e.path().filename(), ec);
    }
    static const std::string keep = d.string();
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(keep, ec);
    });
    return d.string() + "/";
  }();
  return dir;
}

/// Writes the input to work_dir()/name and returns the path.
inline std::string write_input(const std::string& name, const std::uint8_t* data, std::size_t size) {
  const std::string path = work_dir() + name;
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

}  // namespace kfuzz
