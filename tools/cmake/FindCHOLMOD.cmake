# SPDX-License-Identifier: MIT
# find_package(CHOLMOD): SuiteSparse's sparse Cholesky (Debian libsuitesparse-dev,
# which ships no CMake package of its own) on OpenBLAS (libopenblas-dev), as the
# imported target CHOLMOD::CHOLMOD. OpenBLAS is linked by name, not only through
# CHOLMOD's generic libblas, because the direct solver sets its thread count
# (sim/src/cpu/direct.c). CHOLMOD_LIBRARIES_PRIVATE lists what libcholmod itself
# links, for a fully static link (pkg-config --static).
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(CHOLMOD_LIBRARY cholmod)
find_library(CHOLMOD_OPENBLAS_LIBRARY openblas PATH_SUFFIXES openblas-pthread openblas-openmp openblas)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(CHOLMOD REQUIRED_VARS CHOLMOD_LIBRARY CHOLMOD_INCLUDE_DIR CHOLMOD_OPENBLAS_LIBRARY)
mark_as_advanced(CHOLMOD_INCLUDE_DIR CHOLMOD_LIBRARY CHOLMOD_OPENBLAS_LIBRARY)

if(CHOLMOD_FOUND)
  set(CHOLMOD_LIBRARIES_PRIVATE amd colamd camd ccolamd suitesparseconfig lapack blas)
  if(NOT TARGET CHOLMOD::CHOLMOD)
    add_library(CHOLMOD::CHOLMOD UNKNOWN IMPORTED)
    set_target_properties(CHOLMOD::CHOLMOD PROPERTIES IMPORTED_LOCATION "${CHOLMOD_LIBRARY}"
                          INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}"
                          INTERFACE_LINK_LIBRARIES "${CHOLMOD_OPENBLAS_LIBRARY}")
  endif()
endif()
