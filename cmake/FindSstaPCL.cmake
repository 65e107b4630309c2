# Finds just the PCL pieces SSTA uses (pcl_common and pcl_stereo) and defines the imported
# target ssta::pcl. Debian's PCLConfig.cmake pulls in VTK, Qt and MPI targets through pcl_io,
# and fails to configure without MPI's CMake targets; none of that is needed here.
find_path(SSTA_PCL_INCLUDE_DIR pcl/stereo/stereo_matching.h
          PATH_SUFFIXES pcl-1.13 pcl-1.14 pcl-1.12)
find_library(SSTA_PCL_STEREO_LIBRARY NAMES pcl_stereo)
find_library(SSTA_PCL_COMMON_LIBRARY NAMES pcl_common)
find_package(Boost REQUIRED)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(SstaPCL
  REQUIRED_VARS SSTA_PCL_INCLUDE_DIR SSTA_PCL_STEREO_LIBRARY SSTA_PCL_COMMON_LIBRARY)

if(SstaPCL_FOUND AND NOT TARGET ssta::pcl)
  add_library(ssta::pcl INTERFACE IMPORTED)
  set_target_properties(ssta::pcl PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${SSTA_PCL_INCLUDE_DIR};${Boost_INCLUDE_DIRS}"
    INTERFACE_LINK_LIBRARIES "${SSTA_PCL_STEREO_LIBRARY};${SSTA_PCL_COMMON_LIBRARY};Eigen3::Eigen")
endif()
