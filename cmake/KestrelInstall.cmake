# Install rules and the exported CMake package `kestrel`, so another project (firmware or
# desktop) can
#     find_package(kestrel 0.1 REQUIRED)                  # C++ core + C API (Eigen 3.4 needed)
#     find_package(kestrel 0.1 REQUIRED COMPONENTS capi)  # C API only (no Eigen)
#     target_link_libraries(app PRIVATE kestrel::capi)   # or kestrel::controllers, ::allocation ...
# and a firmware project can cross-compile with the installed toolchain files:
#     cmake -DCMAKE_TOOLCHAIN_FILE=<prefix>/share/kestrel/cmake/toolchain-cortex-m4f.cmake ...
# Layout: <prefix>/include (headers), <prefix>/lib (static libraries), <prefix>/lib/cmake/kestrel
# (kestrelConfig.cmake, kestrelTargets.cmake), <prefix>/share/kestrel/cmake (toolchain files),
# <prefix>/bin/kestrel (host builds with sim/).
# A package is per target: install the host build and each MCU build into its own prefix.
# Tests and benchmarks are not installed. The desktop harness (sim/) is not exported yet; its
# command, `kestrel`, is installed. Checked by the packaging ctests (tests/packaging/).
#
# The package carries usage requirements only (docs/packaging.md): include directories, the ABI
# define (kestrel::abi), Eigen for the C++ headers (kestrel::eigen, defined by kestrelConfig.cmake:
# a C consumer of kestrel::capi needs no Eigen), and the link dependencies a consumer of the
# static libraries needs whatever its linker driver (kestrel::cxx_runtime: libm and the C++
# runtime). None of the project's warning or determinism flags (cmake/KestrelFlags.cmake).
include_guard(GLOBAL)
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(KESTREL_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/kestrel" CACHE STRING "Where kestrelConfig.cmake goes")
set(KESTREL_INSTALL_TOOLCHAINDIR "${CMAKE_INSTALL_DATADIR}/kestrel/cmake" CACHE STRING "Where the toolchain files go")

# Libraries exported by name (kestrel::<name without the kestrel_ prefix>). kestrel_abi carries
# KESTREL_USE_DOUBLE; kestrel_cxx_runtime libm and the C++ runtime; kestrel_core_flags is empty
# in the package (a $<LINK_ONLY:> entry of the static libraries' link interface, so it must be
# exported too).
set(_kestrel_export_targets kestrel_abi kestrel_cxx_runtime kestrel_core_flags kestrel_kernel kestrel_controllers
    kestrel_allocation kestrel_robots kestrel_policy kestrel_platform kestrel_capi)
foreach(_t kestrel_sensors kestrel_assert_default)
  if(TARGET ${_t})
    list(APPEND _kestrel_export_targets ${_t})
  endif()
endforeach()
foreach(_t IN LISTS _kestrel_export_targets)
  string(REGEX REPLACE "^kestrel_" "" _name "${_t}")
  set_target_properties(${_t} PROPERTIES EXPORT_NAME ${_name})
  get_target_property(_type ${_t} TYPE)
  if(NOT _type STREQUAL "INTERFACE_LIBRARY")
    target_include_directories(${_t} INTERFACE $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  endif()
endforeach()
# The kernel's assertion hook (kestrel_platform_assert_default) comes from the platform: on the
# host kestrel::platform defines it (print, abort); on bare metal kestrel::assert_default, a weak
# definition that traps, which a firmware replaces by defining the function itself. Installed
# consumers get it with the kernel, so a firmware links with no hook of its own.
if(KESTREL_BOARD STREQUAL "host")
  target_link_libraries(kestrel_kernel INTERFACE $<INSTALL_INTERFACE:kestrel::platform>)
else()
  target_link_libraries(kestrel_kernel INTERFACE $<INSTALL_INTERFACE:kestrel::assert_default>)
endif()

# `cmake --install` copies what the build made; a tree built only for some targets (the example
# script builds the firmware images) lacks libraries. kestrel_package builds everything the install
# needs, and the install says so instead of failing on a missing file.
add_custom_target(kestrel_package)
set(_kestrel_installed_files "")
foreach(_t IN LISTS _kestrel_export_targets)
  get_target_property(_type ${_t} TYPE)
  if(NOT _type STREQUAL "INTERFACE_LIBRARY")
    add_dependencies(kestrel_package ${_t})
    list(APPEND _kestrel_installed_files "$<TARGET_FILE:${_t}>")
  endif()
endforeach()
if(TARGET kestrel)
  add_dependencies(kestrel_package kestrel)
  list(APPEND _kestrel_installed_files "$<TARGET_FILE:kestrel>")
endif()
install(CODE "
  foreach(_f ${_kestrel_installed_files})
    if(NOT EXISTS \"\${_f}\")
      message(FATAL_ERROR \"kestrel: \${_f} has not been built. Build the package first: \"
        \"cmake --build ${CMAKE_BINARY_DIR} --target kestrel_package (or the whole tree).\")
    endif()
  endforeach()")
install(TARGETS ${_kestrel_export_targets} EXPORT kestrelTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

# The simulation harness's command, on PATH as <prefix>/bin/kestrel (host builds with sim/; the
# Python package installs its own `kestrel` console script: python/).
if(TARGET kestrel)
  install(TARGETS kestrel RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

# Headers: every layer's include/ tree (kestrel/<layer>/...), the C API's kestrel/kestrel.h.
foreach(_dir kernel controllers allocation robots policy sensors platform platform/capi)
  if(EXISTS "${PROJECT_SOURCE_DIR}/${_dir}/include/kestrel")
    install(DIRECTORY "${PROJECT_SOURCE_DIR}/${_dir}/include/kestrel" DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  endif()
endforeach()

install(EXPORT kestrelTargets NAMESPACE kestrel:: DESTINATION ${KESTREL_INSTALL_CMAKEDIR})
configure_package_config_file("${CMAKE_CURRENT_LIST_DIR}/package/kestrelConfig.cmake.in"
  "${PROJECT_BINARY_DIR}/kestrelConfig.cmake"
  INSTALL_DESTINATION ${KESTREL_INSTALL_CMAKEDIR}
  PATH_VARS KESTREL_INSTALL_TOOLCHAINDIR)
write_basic_package_version_file("${PROJECT_BINARY_DIR}/kestrelConfigVersion.cmake"
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES "${PROJECT_BINARY_DIR}/kestrelConfig.cmake" "${PROJECT_BINARY_DIR}/kestrelConfigVersion.cmake"
  DESTINATION ${KESTREL_INSTALL_CMAKEDIR})
# Toolchain files are self-contained (they read no project variable and include each other by
# CMAKE_CURRENT_LIST_DIR), so they work from the install location as they are.
install(FILES
  "${PROJECT_SOURCE_DIR}/cmake/toolchain-arm-none-eabi.cmake"
  "${PROJECT_SOURCE_DIR}/cmake/toolchain-cortex-m3.cmake"
  "${PROJECT_SOURCE_DIR}/cmake/toolchain-cortex-m4f.cmake"
  "${PROJECT_SOURCE_DIR}/cmake/toolchain-cortex-m7.cmake"
  "${PROJECT_SOURCE_DIR}/cmake/toolchain-stm32f405.cmake"
  DESTINATION ${KESTREL_INSTALL_TOOLCHAINDIR})
