# SPDX-License-Identifier: MIT
# The installed package, so that other programs can link fascia: the CMake
# package (find_package(fascia): fascia::sim, fascia::prep), its version file,
# and fascia.pc for pkg-config. fascia::sim is the static archive, whose
# config finds what it links again; fascia::sim_shared the shared library.
include(CMakePackageConfigHelpers)
set(FASCIA_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/fascia)

install(EXPORT fasciaTargets NAMESPACE fascia:: DESTINATION ${FASCIA_CMAKE_DIR})
if(FASCIA_HAVE_PREP)
  install(EXPORT fasciaPrepTargets NAMESPACE fascia:: DESTINATION ${FASCIA_CMAKE_DIR})
  install(FILES ${PROJECT_SOURCE_DIR}/tools/cmake/fasciaPrepDependencies.cmake DESTINATION ${FASCIA_CMAKE_DIR})
endif()
set(FASCIA_CONFIG_OPENMP OFF)
if(OpenMP_C_FOUND)
  set(FASCIA_CONFIG_OPENMP ON)
endif()
configure_package_config_file(${PROJECT_SOURCE_DIR}/tools/cmake/fasciaConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/fasciaConfig.cmake INSTALL_DESTINATION ${FASCIA_CMAKE_DIR})
# 0.x: a minor version may change the API
write_basic_package_version_file(${PROJECT_BINARY_DIR}/fasciaConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/fasciaConfig.cmake ${PROJECT_BINARY_DIR}/fasciaConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/tools/cmake/FindCHOLMOD.cmake DESTINATION ${FASCIA_CMAKE_DIR})

# fascia.pc: Libs names the shared library alone (it carries what it
# links); Libs.private what the static archive needs in a static link, as
# library names and pkg-config modules, never a folder of this machine (a
# library outside the linker's default folders comes through its own .pc,
# Requires.private; the CUDA runtime's folder is the user's toolkit's).
function(fascia_pc_names out)
  set(flags "")
  foreach(lib IN LISTS ARGN)
    if(lib MATCHES "^-")
      list(APPEND flags "${lib}")
    else()
      get_filename_component(name "${lib}" NAME)
      string(REGEX REPLACE "^lib" "" name "${name}")
      string(REGEX REPLACE "\\.(so[.0-9]*|a)$" "" name "${name}")
      list(APPEND flags "-l${name}")
    endif()
  endforeach()
  list(REMOVE_DUPLICATES flags)
  list(JOIN flags " " flags)
  set(${out} "${flags}" PARENT_SCOPE)
endfunction()

# what libfascia_sim.a calls directly: libhdf5 (its module hdf5, else the
# name), zlib for compressed VTK files (module zlib, else z), libcholmod and
# OpenBLAS (module openblas, else the name), OpenMP's
# runtime, the CUDA runtime (static, with what it needs) and the C++ runtime
# for the launcher, libm; then what libcholmod needs
find_package(PkgConfig QUIET)
set(FASCIA_PC_REQUIRES_PRIVATE "")
set(direct "")
foreach(module hdf5 openblas zlib)
  set(found FALSE)
  if(PKG_CONFIG_FOUND)
    execute_process(COMMAND ${PKG_CONFIG_EXECUTABLE} --exists ${module} RESULT_VARIABLE missing)
    if(missing EQUAL 0)
      list(APPEND FASCIA_PC_REQUIRES_PRIVATE ${module})
      set(found TRUE)
    endif()
  endif()
  if(NOT found AND module STREQUAL "zlib")
    list(APPEND direct z)
  elseif(NOT found)
    list(APPEND direct ${module})
  endif()
endforeach()
list(JOIN FASCIA_PC_REQUIRES_PRIVATE " " FASCIA_PC_REQUIRES_PRIVATE)
list(APPEND direct cholmod)
if(OpenMP_C_FOUND)
  list(APPEND direct ${OpenMP_C_FLAGS})
endif()
if(FASCIA_HAVE_CUDA)
  list(APPEND direct cudart_static dl rt pthread stdc++)
endif()
list(APPEND direct m ${CHOLMOD_LIBRARIES_PRIVATE})
fascia_pc_names(FASCIA_PC_LIBS_PRIVATE ${direct})
# relative to the .pc file, so that the file is right wherever the tree is
# installed (cmake --install --prefix, DESTDIR)
set(pc_dir ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
file(RELATIVE_PATH FASCIA_PC_UP /root/${pc_dir} /root)
string(REGEX REPLACE "/$" "" FASCIA_PC_UP "${FASCIA_PC_UP}")
configure_file(${PROJECT_SOURCE_DIR}/tools/cmake/fascia.pc.in ${PROJECT_BINARY_DIR}/fascia.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/fascia.pc DESTINATION ${pc_dir})
