// Host implementation of test_io.hpp (stdio, getenv).
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "test_io.hpp"

#ifndef KESTREL_GOLDEN_DIR_DEFAULT
#error "the build must define KESTREL_GOLDEN_DIR_DEFAULT"
#endif

namespace ktest {
namespace {
constexpr int kMaxFiles = 8;
std::FILE* g_files[kMaxFiles] = {};
char g_path[1024];
}  // namespace

int file_open(const char* path) {
  for (int i = 0; i < kMaxFiles; ++i) {
    if (g_files[i] == nullptr) {
      g_files[i] = std::fopen(path, "rb");
      return g_files[i] != nullptr ? i : -1;
    }
  }
  return -1;
}

long file_read(int h, void* buf, std::size_t n) {
  if (h < 0 || h >= kMaxFiles || g_files[h] == nullptr) return -1;
  return static_cast<long>(std::fread(buf, 1, n, g_files[h]));
}

void file_close(int h) {
  if (h < 0 || h >= kMaxFiles || g_files[h] == nullptr) return;
  std::fclose(g_files[h]);
  g_files[h] = nullptr;
}

const char* golden_dir() {
  const char* env = std::getenv("KESTREL_GOLDEN_DIR");
  if (env != nullptr && env[0] != '\0') return env;
  return KESTREL_GOLDEN_DIR_DEFAULT;
}

const char* golden_path(const char* name) {
  std::snprintf(g_path, sizeof(g_path), "%s/%s", golden_dir(), name);
  return g_path;
}

}  // namespace ktest
