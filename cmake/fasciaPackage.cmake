# SPDX-License-Identifier: MIT
# The installed package, so that other programs can link fascia: the CMake
# package (find_package(fascia): fascia::sim, fascia::prep), its version file,
# and fascia.pc for pkg-config. The libraries are static, so both carry what
# the archives link: the config finds it again, the .pc file lists it.
include(CMakePackageConfigHelpers)
set(FASCIA_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/fascia)

install(EXPORT fasciaTargets NAMESPACE fascia:: DESTINATION ${FASCIA_CMAKE_DIR})
if(FASCIA_HAVE_PREP)
  install(EXPORT fasciaPrepTargets NAMESPACE fascia:: DESTINATION ${FASCIA_CMAKE_DIR})
  install(FILES ${PROJECT_SOURCE_DIR}/cmake/fasciaPrepDependencies.cmake DESTINATION ${FASCIA_CMAKE_DIR})
endif()
set(FASCIA_CONFIG_OPENMP OFF)
if(OpenMP_C_FOUND)
  set(FASCIA_CONFIG_OPENMP ON)
endif()
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/fasciaConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/fasciaConfig.cmake INSTALL_DESTINATION ${FASCIA_CMAKE_DIR})
# 0.x: a minor version may change the API
write_basic_package_version_file(${PROJECT_BINARY_DIR}/fasciaConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/fasciaConfig.cmake ${PROJECT_BINARY_DIR}/fasciaConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/FindCHOLMOD.cmake DESTINATION ${FASCIA_CMAKE_DIR})

# Link flags for pkg-config from a CMake library list: a file path becomes
# -L<dir> -l<name> (no -L for the compiler's own folders), a name -l<name>,
# a flag stays as it is.
function(fascia_pc_flags out)
  set(flags "")
  foreach(lib IN LISTS ARGN)
    if(lib MATCHES "^-")
      list(APPEND flags "${lib}")
    elseif(IS_ABSOLUTE "${lib}")
      get_filename_component(dir "${lib}" DIRECTORY)
      get_filename_component(name "${lib}" NAME)
      string(REGEX REPLACE "^lib" "" name "${name}")
      string(REGEX REPLACE "\\.(so[.0-9]*|a)$" "" name "${name}")
      if(NOT dir IN_LIST CMAKE_C_IMPLICIT_LINK_DIRECTORIES)
        list(APPEND flags "-L${dir}")
      endif()
      list(APPEND flags "-l${name}")
    else()
      list(APPEND flags "-l${lib}")
    endif()
  endforeach()
  list(REMOVE_DUPLICATES flags)
  list(JOIN flags " " flags)
  set(${out} "${flags}" PARENT_SCOPE)
endfunction()

# what libfascia_sim.a calls directly: libhdf5, libcholmod and OpenBLAS, OpenMP's
# runtime, the CUDA runtime (static, with what it needs) and the C++ runtime for
# the launcher, libm
set(hdf5_direct ${HDF5_C_LIBRARY_hdf5})
if(NOT hdf5_direct)
  list(GET HDF5_C_LIBRARIES 0 hdf5_direct)
endif()
set(hdf5_rest ${HDF5_C_LIBRARIES})
list(REMOVE_ITEM hdf5_rest ${hdf5_direct})
set(direct ${hdf5_direct} ${CHOLMOD_LIBRARY} ${CHOLMOD_OPENBLAS_LIBRARY})
if(OpenMP_C_FOUND)
  list(APPEND direct ${OpenMP_C_FLAGS})
endif()
if(FASCIA_HAVE_CUDA)
  list(APPEND direct ${CUDA_cudart_static_LIBRARY} dl rt pthread stdc++)
endif()
list(APPEND direct m)
fascia_pc_flags(FASCIA_PC_LIBS ${direct})
fascia_pc_flags(FASCIA_PC_LIBS_PRIVATE ${hdf5_rest} ${CHOLMOD_LIBRARIES_PRIVATE})
# relative to the .pc file, so that the file is right wherever the tree is
# installed (cmake --install --prefix, DESTDIR)
set(pc_dir ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
file(RELATIVE_PATH FASCIA_PC_UP /root/${pc_dir} /root)
string(REGEX REPLACE "/$" "" FASCIA_PC_UP "${FASCIA_PC_UP}")
configure_file(${PROJECT_SOURCE_DIR}/cmake/fascia.pc.in ${PROJECT_BINARY_DIR}/fascia.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/fascia.pc DESTINATION ${pc_dir})
