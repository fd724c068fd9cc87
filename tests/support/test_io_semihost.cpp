// MCU implementation of test_io.hpp: host files through ARM semihosting (SYS_OPEN / SYS_READ /
// SYS_CLOSE), the golden directory from the semihosting command line (SYS_GET_CMDLINE).
//
// run-qemu.sh starts QEMU with `-semihosting-config enable=on,target=native,arg=<name>,arg=<dir>`;
// QEMU joins the arguments with spaces, so the command line is "<name> <dir>": everything after
// the first space is the directory (which may itself contain spaces). Without a second argument
// the build's KESTREL_GOLDEN_DIR_DEFAULT is used.
#include <cstring>

#include "kestrel/platform/semihosting.hpp"
#include "test_io.hpp"

#ifndef KESTREL_GOLDEN_DIR_DEFAULT
#error "the build must define KESTREL_GOLDEN_DIR_DEFAULT"
#endif

namespace ktest {
namespace {
namespace semihost = kestrel::platform::semihost;

char g_cmdline[1024];
const char* g_golden = nullptr;
char g_path[1024];

}  // namespace

int file_open(const char* path) { return semihost::open(path, semihost::kModeRB); }

long file_read(int handle, void* buf, std::size_t n) {
  if (handle < 0) return -1;
  return semihost::read(handle, buf, n);  // one trap per call: callers read in chunks (4 KiB)
}

void file_close(int handle) {
  if (handle >= 0) semihost::close(handle);
}

const char* golden_dir() {
  if (g_golden != nullptr) return g_golden;
  g_golden = KESTREL_GOLDEN_DIR_DEFAULT;
  if (semihost::get_cmdline(g_cmdline, sizeof(g_cmdline)) > 0) {
    char* dir = std::strchr(g_cmdline, ' ');
    if (dir != nullptr) {
      while (*dir == ' ') ++dir;
      std::size_t len = std::strlen(dir);
      while (len > 0 && dir[len - 1] == ' ') dir[--len] = '\0';
      if (len > 0) g_golden = dir;
    }
  }
  return g_golden;
}

const char* golden_path(const char* name) {
  const char* dir = golden_dir();
  const std::size_t nd = std::strlen(dir), nn = std::strlen(name);
  if (nd + 1 + nn + 1 > sizeof(g_path)) {
    g_path[0] = '\0';  // too long: opening "" fails like a missing file
    return g_path;
  }
  std::memcpy(g_path, dir, nd);
  g_path[nd] = '/';
  std::memcpy(g_path + nd + 1, name, nn + 1);
  return g_path;
}

}  // namespace ktest
