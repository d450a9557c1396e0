# install.cmake - what `cmake --install` (and `make install`) puts under the prefix:
#   lib/libmpm.so*          the shared library (MPM_SHARED), public API only
#   lib/libmpm.a            the static library
#   lib/libmpmvdb.so        with OpenVDB: the shim both libraries open (dlopen) at the first
#                           particle surface, from beside themselves
#   include/mpm/mpm.h       the public header, and scene_def.h, render.h and plot.h, which it
#                           includes
#   bin/mpm                 the program (MPM_BUILD_PROGRAM)
#   lib/pkgconfig/mpm.pc    pkg-config: `pkg-config --cflags --libs mpm` (shared), --static lists
#                           what libmpm.a needs
#   lib/cmake/mpm/          the CMake package: find_package(mpm) gives mpm::mpm (shared) and
#                           mpm::mpm_static
# Every path in the pkg-config file and the package is relative to where they are installed, so
# `cmake --install BUILD --prefix P` may choose another prefix than the configured one.
# Included from CMakeLists.txt when MPM_INSTALL is on.
include(CMakePackageConfigHelpers)

set(MPM_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/mpm)
set(MPM_INSTALL_TARGETS mpmcore)
if(MPM_SHARED)
  list(APPEND MPM_INSTALL_TARGETS mpm_shared)
endif()
install(TARGETS ${MPM_INSTALL_TARGETS} EXPORT mpmTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
if(MPM_OPENVDB)
  # the OpenVDB module, built here or in another build tree (MPM_VDB_SHIM_LIBRARY) alike: both
  # libraries open it from beside themselves (src/surface/vdb_load.c)
  install(FILES ${MPM_VDB_MODULE_FILE} DESTINATION ${CMAKE_INSTALL_LIBDIR} RENAME libmpmvdb.so)
endif()
install(FILES ${PROJECT_SOURCE_DIR}/include/mpm/mpm.h ${PROJECT_SOURCE_DIR}/include/mpm/scene_def.h
              ${PROJECT_SOURCE_DIR}/include/mpm/render.h ${PROJECT_SOURCE_DIR}/include/mpm/plot.h
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/mpm)
if(MPM_BUILD_PROGRAM)
  install(TARGETS mpm RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

# ---- the CMake package ----
# the Blender add-on, as a folder to copy into Blender's add-ons (docs/houdini-blender.md)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/blender/io_import_mpm_run
        DESTINATION ${CMAKE_INSTALL_DATADIR}/mpm/blender FILES_MATCHING PATTERN "*.py")
install(EXPORT mpmTargets NAMESPACE mpm:: DESTINATION ${MPM_CMAKE_DIR})
if(MPM_DOUBLE)
  set(MPM_REAL_TYPE double)
else()
  set(MPM_REAL_TYPE float)
endif()
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/mpmConfig.cmake.in
  ${PROJECT_BINARY_DIR}/mpmConfig.cmake INSTALL_DESTINATION ${MPM_CMAKE_DIR})
# the ABI may change with every minor version before 1.0 (the SOVERSION is 0.MINOR)
if(PROJECT_VERSION_MAJOR EQUAL 0)
  set(MPM_COMPATIBILITY SameMinorVersion)
else()
  set(MPM_COMPATIBILITY SameMajorVersion)
endif()
write_basic_package_version_file(${PROJECT_BINARY_DIR}/mpmConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY ${MPM_COMPATIBILITY})
install(FILES ${PROJECT_BINARY_DIR}/mpmConfig.cmake ${PROJECT_BINARY_DIR}/mpmConfigVersion.cmake
        DESTINATION ${MPM_CMAKE_DIR})

# ---- pkg-config ----
# prefix from the file's own place: lib/pkgconfig -> ../..
file(RELATIVE_PATH MPM_PC_PREFIX /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
set(MPM_PC_REQUIRES_PRIVATE "libcjson libpng hdf5-serial")
set(MPM_PC_LIBS_PRIVATE "")
if(MPM_OPENVDB)
  string(APPEND MPM_PC_LIBS_PRIVATE " -ldl") # dlopen of libmpmvdb.so
endif()
if(MPM_OPENMP)
  string(APPEND MPM_PC_LIBS_PRIVATE " ${OpenMP_C_FLAGS}")
endif()
string(APPEND MPM_PC_LIBS_PRIVATE " -lm")
string(STRIP "${MPM_PC_LIBS_PRIVATE}" MPM_PC_LIBS_PRIVATE)
configure_file(${CMAKE_CURRENT_LIST_DIR}/mpm.pc.in ${PROJECT_BINARY_DIR}/mpm.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/mpm.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
