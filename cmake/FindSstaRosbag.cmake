# Finds Debian's ROS 1 bag library (librosbag-dev: rosbag_storage and the serialization and time
# libraries its headers use) and defines the imported target ssta::rosbag. rosbag_storage.pc
# requires pluginlib.pc, which Debian's pluginlib package does not ship, so pkg-config cannot be
# used; the catkin CMake configs pull in far more than reading a bag needs.
find_path(SSTA_ROSBAG_INCLUDE_DIR rosbag/bag.h)
# rosbag/bag.h includes pluginlib, which includes class_loader, rcpputils, rcutils and
# ament_index_cpp: Debian installs each one folder down (/usr/include/NAME/NAME/...).
set(SSTA_ROSBAG_INCLUDE_DIRS ${SSTA_ROSBAG_INCLUDE_DIR})
foreach(header pluginlib/class_loader.hpp class_loader/class_loader.hpp rcpputils/shared_library.hpp
               rcutils/types.h ament_index_cpp/get_package_prefix.hpp)
  get_filename_component(package ${header} DIRECTORY)
  string(TOUPPER ${package} upper)
  find_path(SSTA_${upper}_INCLUDE_DIR ${header} PATH_SUFFIXES ${package})
  list(APPEND SSTA_ROSBAG_INCLUDE_DIRS ${SSTA_${upper}_INCLUDE_DIR})
  list(APPEND SSTA_ROSBAG_REQUIRED SSTA_${upper}_INCLUDE_DIR)
endforeach()
find_library(SSTA_ROSBAG_STORAGE_LIBRARY NAMES rosbag_storage)
find_library(SSTA_ROSCPP_SERIALIZATION_LIBRARY NAMES roscpp_serialization)
find_library(SSTA_ROSTIME_LIBRARY NAMES rostime)
find_library(SSTA_CONSOLE_BRIDGE_LIBRARY NAMES console_bridge)
find_library(SSTA_CPP_COMMON_LIBRARY NAMES cpp_common)
find_package(Boost REQUIRED)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(SstaRosbag
  REQUIRED_VARS SSTA_ROSBAG_INCLUDE_DIR ${SSTA_ROSBAG_REQUIRED} SSTA_ROSBAG_STORAGE_LIBRARY SSTA_ROSCPP_SERIALIZATION_LIBRARY
                SSTA_ROSTIME_LIBRARY SSTA_CONSOLE_BRIDGE_LIBRARY SSTA_CPP_COMMON_LIBRARY)

if(SstaRosbag_FOUND AND NOT TARGET ssta::rosbag)
  add_library(ssta::rosbag INTERFACE IMPORTED)
  set_target_properties(ssta::rosbag PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${SSTA_ROSBAG_INCLUDE_DIRS};${Boost_INCLUDE_DIRS}"
    INTERFACE_LINK_LIBRARIES
      "${SSTA_ROSBAG_STORAGE_LIBRARY};${SSTA_ROSCPP_SERIALIZATION_LIBRARY};${SSTA_ROSTIME_LIBRARY};${SSTA_CONSOLE_BRIDGE_LIBRARY};${SSTA_CPP_COMMON_LIBRARY}")
endif()
