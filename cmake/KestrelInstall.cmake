# Install rules and the exported CMake package `kestrel`, so another project (firmware or
# desktop) can
#     find_package(kestrel 0.1 REQUIRED)
#     target_link_libraries(app PRIVATE kestrel::capi)   # or kestrel::controllers, ::allocation ...
# and a firmware project can cross-compile with the installed toolchain files:
#     cmake -DCMAKE_TOOLCHAIN_FILE=<prefix>/share/kestrel/cmake/toolchain-cortex-m4f.cmake ...
# Layout: <prefix>/include (headers), <prefix>/lib (static libraries), <prefix>/lib/cmake/kestrel
# (kestrelConfig.cmake, kestrelTargets.cmake), <prefix>/share/kestrel/cmake (toolchain files).
# A package is per target: install the host build and each MCU build into its own prefix.
# Tests and benchmarks are not installed. The desktop harness (sim/) is not exported yet.
include_guard(GLOBAL)
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(KESTREL_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/kestrel" CACHE STRING "Where kestrelConfig.cmake goes")
set(KESTREL_INSTALL_TOOLCHAINDIR "${CMAKE_INSTALL_DATADIR}/kestrel/cmake" CACHE STRING "Where the toolchain files go")

# Libraries exported by name (kestrel::<name without the kestrel_ prefix>). kestrel_flags carries
# the determinism flags and KESTREL_USE_DOUBLE to consumers; kestrel_core_flags is only a
# link-time dependency of the core libraries' (empty) link interface but must be exported too.
set(_kestrel_export_targets kestrel_flags kestrel_core_flags kestrel_kernel kestrel_controllers kestrel_allocation
    kestrel_robots kestrel_policy kestrel_platform kestrel_capi)
if(TARGET kestrel_sensors)
  list(APPEND _kestrel_export_targets kestrel_sensors)
endif()
foreach(_t IN LISTS _kestrel_export_targets)
  string(REGEX REPLACE "^kestrel_" "" _name "${_t}")
  set_target_properties(${_t} PROPERTIES EXPORT_NAME ${_name})
  get_target_property(_type ${_t} TYPE)
  if(NOT _type STREQUAL "INTERFACE_LIBRARY")
    target_include_directories(${_t} INTERFACE $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  endif()
endforeach()
# The kernel's assertion hook (kestrel_platform_assert_default) comes from the platform: on the
# host kestrel::platform defines it, so installed consumers get it with the kernel; bare-metal
# firmware defines it itself (or links Kestrel's Cortex-M runtime in a Kestrel-built image).
if(KESTREL_BOARD STREQUAL "host")
  target_link_libraries(kestrel_kernel INTERFACE $<INSTALL_INTERFACE:kestrel::platform>)
endif()
install(TARGETS ${_kestrel_export_targets} EXPORT kestrelTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

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
