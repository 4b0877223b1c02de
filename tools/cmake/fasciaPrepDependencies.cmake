# SPDX-License-Identifier: MIT
# Finds what the preprocessing library links: assimp, CGAL, OpenVDB, cJSON and
# nettle. Used twice, so the two cannot drift: by prep/CMakeLists.txt when
# fascia is built, and by the installed fasciaConfig.cmake before it loads
# fascia::prep (a static archive, whose private libraries its users link).
# Sets fascia_prep_missing to the list of what was not found, with the Debian
# package that has it; the callers decide whether that is an error; and
# fascia_prep_labelmap_missing to what label-map reading lacks.
set(fascia_prep_missing "")
# Debian's FindOpenVDB.cmake lives outside CMake's module path, and sets
# BUILD_SHARED_LIBS in its caller's scope: keep both as the caller had them.
set(_fascia_module_path "${CMAKE_MODULE_PATH}")
list(APPEND CMAKE_MODULE_PATH /usr/lib/x86_64-linux-gnu/cmake/OpenVDB /usr/lib/cmake/OpenVDB
     /usr/local/lib/cmake/OpenVDB)
set(_fascia_had_shared OFF)
if(DEFINED BUILD_SHARED_LIBS)
  set(_fascia_had_shared ON)
  set(_fascia_shared "${BUILD_SHARED_LIBS}")
endif()

find_package(assimp QUIET)
if(NOT assimp_FOUND)
  list(APPEND fascia_prep_missing "assimp (libassimp-dev)")
endif()
# CGAL prints a warning about the build type unless told it is fine
set(CGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE TRUE)
find_package(CGAL QUIET)
if(NOT CGAL_FOUND)
  list(APPEND fascia_prep_missing "CGAL (libcgal-dev)")
endif()
# Debian's FindOpenVDB.cmake asks for Boost iostreams' CMake files as REQUIRED
# (a hard configure error without libboost-iostreams-dev). So: use it only
# when Boost iostreams is findable, else import the library by hand (its
# runtime needs only the shared libboost_iostreams, which libopenvdb links).
if(NOT TARGET OpenVDB::openvdb)
  find_package(Boost QUIET COMPONENTS iostreams)
  if(Boost_IOSTREAMS_FOUND OR Boost_iostreams_FOUND)
    find_package(OpenVDB QUIET)
  endif()
endif()
if(NOT TARGET OpenVDB::openvdb)
  find_path(FASCIA_OPENVDB_INCLUDE_DIR openvdb/openvdb.h)
  find_library(FASCIA_OPENVDB_LIBRARY openvdb)
  find_package(TBB QUIET CONFIG)
  find_package(Imath QUIET CONFIG) # OpenVDB's half type comes from Imath in Debian's build
  if(FASCIA_OPENVDB_INCLUDE_DIR AND FASCIA_OPENVDB_LIBRARY AND TARGET TBB::tbb)
    set(_fascia_vdb_deps TBB::tbb)
    if(TARGET Imath::Imath)
      list(APPEND _fascia_vdb_deps Imath::Imath)
    endif()
    add_library(OpenVDB::openvdb UNKNOWN IMPORTED)
    set_target_properties(OpenVDB::openvdb PROPERTIES IMPORTED_LOCATION ${FASCIA_OPENVDB_LIBRARY}
                          INTERFACE_INCLUDE_DIRECTORIES ${FASCIA_OPENVDB_INCLUDE_DIR}
                          INTERFACE_LINK_LIBRARIES "${_fascia_vdb_deps}")
    file(STRINGS ${FASCIA_OPENVDB_INCLUDE_DIR}/openvdb/version.h _fascia_vdb_major
         REGEX "define OPENVDB_LIBRARY_MAJOR_VERSION_NUMBER")
    string(REGEX MATCH "[0-9]+" OpenVDB_VERSION "${_fascia_vdb_major}")
  endif()
endif()
if(NOT TARGET OpenVDB::openvdb)
  list(APPEND fascia_prep_missing "OpenVDB (libopenvdb-dev; its FindOpenVDB.cmake folder on CMAKE_MODULE_PATH)")
endif()
if(NOT TARGET cjson)
  find_package(cJSON QUIET)
endif()
if(NOT TARGET cjson)
  list(APPEND fascia_prep_missing "cJSON (libcjson-dev)")
endif()
# A library that ships no CMake files, imported by hand as `target` from its
# header and library (cached as PREFIX_INCLUDE_DIR, PREFIX_LIBRARY); when
# either is not found, `package` is appended to the list `missing`.
macro(_fascia_import_by_hand target prefix header library package missing)
  if(NOT TARGET ${target})
    find_path(${prefix}_INCLUDE_DIR ${header})
    find_library(${prefix}_LIBRARY ${library})
    if(${prefix}_INCLUDE_DIR AND ${prefix}_LIBRARY)
      add_library(${target} UNKNOWN IMPORTED)
      set_target_properties(${target} PROPERTIES IMPORTED_LOCATION ${${prefix}_LIBRARY}
                            INTERFACE_INCLUDE_DIRECTORIES ${${prefix}_INCLUDE_DIR})
    else()
      list(APPEND ${missing} "${package}")
    endif()
  endif()
endmacro()

# nettle: SHA-256 of the inputs for the provenance
_fascia_import_by_hand(fascia::nettle FASCIA_NETTLE nettle/sha2.h nettle "nettle (nettle-dev)" fascia_prep_missing)

# Label maps (optional: without them prep reads meshes only and says so):
# NIfTI's reference library and teem's nrrd. Imported by hand like nettle:
# teem's own CMake files are not on CMake's search path in Debian.
set(fascia_prep_labelmap_missing "")
if(NOT TARGET fascia::nifti2)
  find_path(FASCIA_NIFTI_INCLUDE_DIR nifti2_io.h PATH_SUFFIXES nifti)
  find_library(FASCIA_NIFTI_LIBRARY nifti2)
  find_library(FASCIA_ZNZ_LIBRARY znz)
  if(FASCIA_NIFTI_INCLUDE_DIR AND FASCIA_NIFTI_LIBRARY AND FASCIA_ZNZ_LIBRARY)
    add_library(fascia::nifti2 UNKNOWN IMPORTED GLOBAL)
    set_target_properties(fascia::nifti2 PROPERTIES IMPORTED_LOCATION ${FASCIA_NIFTI_LIBRARY}
                          INTERFACE_INCLUDE_DIRECTORIES ${FASCIA_NIFTI_INCLUDE_DIR}
                          INTERFACE_LINK_LIBRARIES "${FASCIA_ZNZ_LIBRARY};m")
  else()
    list(APPEND fascia_prep_labelmap_missing "NIfTI (libnifti2-dev)")
  endif()
endif()
_fascia_import_by_hand(fascia::teem FASCIA_TEEM teem/nrrd.h teem "teem (libteem-dev)" fascia_prep_labelmap_missing)

set(CMAKE_MODULE_PATH "${_fascia_module_path}")
if(_fascia_had_shared)
  set(BUILD_SHARED_LIBS "${_fascia_shared}")
else()
  unset(BUILD_SHARED_LIBS)
endif()
