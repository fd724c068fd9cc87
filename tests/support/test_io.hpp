// File access and golden-directory lookup for tests that run on the host and on the emulated MCU.
// Host: stdio + getenv. MCU: ARM semihosting (the QEMU wrapper passes the golden directory as a
// semihosting argument), so the emulated core reads the very same JSON files as the host.
#pragma once

#include <cstddef>

namespace ktest {

/// Opens a file for reading; returns a handle >= 0 or -1.
int file_open(const char* path);
/// Reads up to n bytes; returns the count (0 at end of file), or -1 on error.
long file_read(int handle, void* buf, std::size_t n);
void file_close(int handle);

/// Directory holding the golden reference JSON files: KESTREL_GOLDEN_DIR if set, else the
/// build's default (tests/golden/reference, the copy in the repository).
const char* golden_dir();

/// Joins golden_dir() and name into a static buffer.
const char* golden_path(const char* name);

}  // namespace ktest
