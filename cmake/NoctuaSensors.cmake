# Frame sources beyond folders: ROS1 bags (Debian's librosbag-storage-dev and libsensor-msgs-dev)
# and OpenNI2 cameras (libopenni2-dev). Found by their headers and libraries: Debian's
# rosbag_storage CMake and pkg-config files need ROS 2's ament tooling and a pluginlib.pc that
# Debian does not ship. Sets NOCTUA_SENSOR_INCLUDE_DIRS and NOCTUA_SENSOR_LIBRARIES, to be used
# PRIVATE (only src/noctua/io/*.cc include these headers).

find_path(NOCTUA_ROSBAG_INCLUDE_DIR rosbag/bag.h REQUIRED)
find_path(NOCTUA_SENSOR_MSGS_INCLUDE_DIR sensor_msgs/Image.h REQUIRED)
find_path(NOCTUA_OPENNI2_INCLUDE_DIR OpenNI.h PATH_SUFFIXES openni2 REQUIRED)
set(NOCTUA_SENSOR_INCLUDE_DIRS ${NOCTUA_ROSBAG_INCLUDE_DIR} ${NOCTUA_SENSOR_MSGS_INCLUDE_DIR}
                               ${NOCTUA_OPENNI2_INCLUDE_DIR})
# rosbag/bag.h includes ROS 2's pluginlib (for its encryption plugins), which Debian installs
# under include/<package>/ with what it includes in turn.
foreach(header IN ITEMS pluginlib/class_loader.hpp class_loader/class_loader.hpp
                        ament_index_cpp/get_package_prefix.hpp rcutils/logging_macros.h
                        rcpputils/shared_library.hpp)
  string(REGEX REPLACE "/.*" "" package ${header})
  find_path(NOCTUA_${package}_INCLUDE_DIR ${header} PATH_SUFFIXES ${package} REQUIRED)
  list(APPEND NOCTUA_SENSOR_INCLUDE_DIRS ${NOCTUA_${package}_INCLUDE_DIR})
endforeach()
list(REMOVE_DUPLICATES NOCTUA_SENSOR_INCLUDE_DIRS)

set(NOCTUA_SENSOR_LIBRARIES "")
foreach(library IN ITEMS rosbag_storage roscpp_serialization rostime cpp_common console_bridge
                         OpenNI2)
  find_library(NOCTUA_${library}_LIBRARY ${library} REQUIRED)
  list(APPEND NOCTUA_SENSOR_LIBRARIES ${NOCTUA_${library}_LIBRARY})
endforeach()
message(STATUS "noctua: ROS bags and OpenNI2 from ${NOCTUA_SENSOR_LIBRARIES}")
