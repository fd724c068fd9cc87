# Compiler flags shared by every Kestrel target.
#
# kestrel_flags is the project's own policy (warnings as errors, determinism, Eigen's no-heap
# switches, the MCU's no-exceptions build). Every target of this build tree gets it (the kernel
# and the platform pass it on through $<BUILD_INTERFACE:...>), but it is never exported: an
# installed consumer compiles with its own flags. What a consumer must share with the libraries
# is in kestrel_abi (exported as kestrel::abi, passed on by kestrel::kernel).
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
# The ABI: KESTREL_USE_DOUBLE switches `real` (kernel/types.hpp) and with it the layout of every
# C++ struct of the core, so code that includes the core's headers must see the same value as the
# libraries. Nothing else of the policy changes a type, a layout or a signature: EIGEN_NO_MALLOC /
# EIGEN_MPL2_ONLY / EIGEN_NO_DEBUG only add or remove checks in Eigen's inline code, and
# -ffp-contract=off / -fno-math-errno only how the library's own code is compiled.
add_library(kestrel_abi INTERFACE)
if(KESTREL_DOUBLE)
  target_compile_definitions(kestrel_abi INTERFACE KESTREL_USE_DOUBLE=1)
endif()
target_link_libraries(kestrel_flags INTERFACE kestrel_abi)
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
# The static libraries' PRIVATE links are exported as $<LINK_ONLY:...>, so the package carries
# this target too, empty (the option is build-interface only).
add_library(kestrel_core_flags INTERFACE)
if(NOT KESTREL_DOUBLE)
  target_compile_options(kestrel_core_flags INTERFACE $<BUILD_INTERFACE:$<$<COMPILE_LANGUAGE:CXX,C>:-Wdouble-promotion>>)
endif()

# The runtime the static C++ libraries need when the consumer links through the C driver
# (project(x C)): the C++ compiler's implicit link libraries that the C compiler's lack (stdc++
# and m with GCC, libstdc++_nano through nano.specs on the MCU). Exported as kestrel::cxx_runtime
# and listed after the libraries by kestrel::kernel's link interface (a link made by the C++ driver
# names them twice, harmlessly). Bare-metal toolchains detect no implicit libraries (try_compile
# builds a static library there), hence the GNU fallback.
add_library(kestrel_cxx_runtime INTERFACE)
set(_kestrel_cxx_runtime ${CMAKE_CXX_IMPLICIT_LINK_LIBRARIES})
if(CMAKE_C_IMPLICIT_LINK_LIBRARIES)
  list(REMOVE_ITEM _kestrel_cxx_runtime ${CMAKE_C_IMPLICIT_LINK_LIBRARIES})
endif()
if(NOT _kestrel_cxx_runtime AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  set(_kestrel_cxx_runtime stdc++ m)
endif()
list(REMOVE_DUPLICATES _kestrel_cxx_runtime)
foreach(_lib IN LISTS _kestrel_cxx_runtime)
  # Install interface only: in this tree every link is made by the C++ driver, and the MCU images'
  # link lines (and so their layout and instruction counts) stay as they were.
  target_link_libraries(kestrel_cxx_runtime INTERFACE $<INSTALL_INTERFACE:${_lib}>)
endforeach()

if(KESTREL_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=address,undefined)
endif()
