# FindKLU: SuiteSparse's KLU sparse LU (Debian 12 ships no CMake config or pkg-config file for it).
# Defines KLU::KLU (klu plus the amd, colamd, btf and suitesparseconfig it needs). The libraries
# are linked by name from their directories, so that a -static link takes the archives.
find_path(KLU_INCLUDE_DIR klu.h PATH_SUFFIXES suitesparse)
find_library(KLU_LIBRARY klu)
find_library(KLU_AMD_LIBRARY amd)
find_library(KLU_COLAMD_LIBRARY colamd)
find_library(KLU_BTF_LIBRARY btf)
find_library(KLU_CONFIG_LIBRARY suitesparseconfig)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(KLU REQUIRED_VARS
  KLU_LIBRARY KLU_INCLUDE_DIR KLU_AMD_LIBRARY KLU_COLAMD_LIBRARY KLU_BTF_LIBRARY KLU_CONFIG_LIBRARY)

if(KLU_FOUND AND NOT TARGET KLU::KLU)
  add_library(KLU::KLU INTERFACE IMPORTED)
  set(KLU_LIBRARY_DIRS "")
  foreach(library KLU_LIBRARY KLU_AMD_LIBRARY KLU_COLAMD_LIBRARY KLU_BTF_LIBRARY KLU_CONFIG_LIBRARY)
    get_filename_component(directory "${${library}}" DIRECTORY)
    list(APPEND KLU_LIBRARY_DIRS "${directory}")
  endforeach()
  unset(library)
  unset(directory)
  list(REMOVE_DUPLICATES KLU_LIBRARY_DIRS)
  set_target_properties(KLU::KLU PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${KLU_INCLUDE_DIR}"
    INTERFACE_LINK_DIRECTORIES "${KLU_LIBRARY_DIRS}"
    INTERFACE_LINK_LIBRARIES "klu;amd;colamd;btf;suitesparseconfig")
endif()
mark_as_advanced(KLU_INCLUDE_DIR KLU_LIBRARY KLU_AMD_LIBRARY KLU_COLAMD_LIBRARY KLU_BTF_LIBRARY KLU_CONFIG_LIBRARY)
