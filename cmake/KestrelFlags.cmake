# Compiler flags shared by every Kestrel target.
#
# Determinism: -ffp-contract=off everywhere (no fused multiply-add unless written), never
# -ffast-math. -fno-math-errno only lets sqrtf become one instruction; it does not change a value.
# -Wdouble-promotion keeps double arithmetic (software-emulated on a single-precision FPU) out of
# the float core.
add_library(kestrel_flags INTERFACE)
add_library(kestrel::flags ALIAS kestrel_flags)
target_compile_options(kestrel_flags INTERFACE
  -ffp-contract=off -fno-math-errno
  $<$<COMPILE_LANGUAGE:CXX,C>:-Wall -Wextra -Wpedantic -Wshadow -Werror>
  $<$<COMPILE_LANGUAGE:CXX>:-Wnon-virtual-dtor -Wold-style-cast>)
# Eigen must never touch the heap in the core (EIGEN_NO_MALLOC turns a hidden allocation into an
# assertion on the host; on the MCU there is no heap to link against).
target_compile_definitions(kestrel_flags INTERFACE EIGEN_NO_MALLOC EIGEN_MPL2_ONLY)
if(KESTREL_DOUBLE)
  target_compile_definitions(kestrel_flags INTERFACE KESTREL_USE_DOUBLE=1)
endif()
if(NOT KESTREL_BOARD STREQUAL "host")
  # On the MCU everything (core, tests, firmware) is built the way it runs there: no exceptions,
  # no RTTI, no thread-safe statics (no OS).
  target_compile_options(kestrel_flags INTERFACE
    $<$<COMPILE_LANGUAGE:CXX>:-fno-exceptions -fno-rtti -fno-threadsafe-statics>)
  # Eigen's own asserts would pull in newlib's assert -> fprintf -> malloc.
  target_compile_definitions(kestrel_flags INTERFACE EIGEN_NO_DEBUG)
endif()

# Extra rules for the core libraries themselves (linked PRIVATE, so tests are not bound by them):
# -Wdouble-promotion keeps double arithmetic (software-emulated on a single-precision FPU) out of
# the float core.
add_library(kestrel_core_flags INTERFACE)
if(NOT KESTREL_DOUBLE)
  target_compile_options(kestrel_core_flags INTERFACE $<$<COMPILE_LANGUAGE:CXX,C>:-Wdouble-promotion>)
endif()

if(KESTREL_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=address,undefined)
endif()
