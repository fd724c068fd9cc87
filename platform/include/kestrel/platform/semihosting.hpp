// ARM semihosting (Cortex-M only): the program asks the debugger — here QEMU with
// `-semihosting-config enable=on,target=native` — to do I/O on its behalf through `bkpt 0xAB`.
// Kestrel's MCU images use it for the console, for reading the golden files in tests, for the
// command line and for the exit status. Reference: Arm "Semihosting for AArch32 and AArch64",
// version 2.0 (operation numbers and parameter blocks below).
//
// On a real board without a debugger attached, `bkpt` is a HardFault: firmware for hardware
// should use a UART console instead.
#pragma once

#include <cstddef>
#include <cstdint>

namespace kestrel::platform::semihost {

enum Op : std::uint32_t {
  kSysOpen = 0x01,
  kSysClose = 0x02,
  kSysWrite0 = 0x04,
  kSysWrite = 0x05,
  kSysRead = 0x06,
  kSysGetCmdline = 0x15,
  kSysExit = 0x18,
  kSysExitExtended = 0x20,
};

/// Reason codes for SYS_EXIT.
enum Reason : std::uint32_t {
  kAdpStoppedApplicationExit = 0x20026,
  kAdpStoppedRunTimeErrorUnknown = 0x20023,
};

/// SYS_OPEN modes (fopen equivalents).
enum Mode : std::uint32_t { kModeR = 0, kModeRB = 1, kModeW = 4, kModeWB = 5 };

/// One semihosting call: r0 = op, r1 = arg; returns r0.
std::int32_t call(std::uint32_t op, const void* arg);

/// Opens a host file; returns a handle (>= 0) or -1. ":tt" opened for writing is the host's stdout.
int open(const char* path, Mode mode);
int close(int handle);
/// Writes n bytes; returns the number NOT written (0 on success).
std::size_t write(int handle, const void* buf, std::size_t n);
/// Reads up to n bytes; returns the number read (0 at end of file) or -1 on error.
long read(int handle, void* buf, std::size_t n);
/// Writes a NUL-terminated string to the debug console.
void write0(const char* s);
/// The command line (`-semihosting-config ...,arg=a,arg=b` gives "a b"), NUL-terminated into buf;
/// returns its length or -1 (error or too long for cap).
int get_cmdline(char* buf, std::size_t cap);
/// Ends the program. code 0: SYS_EXIT with ADP_Stopped_ApplicationExit (QEMU exits 0). Any other
/// code: SYS_EXIT_EXTENDED with that code as the subcode, so QEMU exits with status code & 0xFF
/// (a multiple of 256 becomes 1, never 0); where SYS_EXIT_EXTENDED is not supported, falls back to
/// SYS_EXIT with ADP_Stopped_RunTimeErrorUnknown (QEMU exits 1).
[[noreturn]] void exit(int code);

}  // namespace kestrel::platform::semihost
