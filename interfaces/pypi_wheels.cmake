# Included by every package under interfaces/ after its rosidl_generate_interfaces().
#
# The PyPI ROS wheels export Python targets whose include directories name the wheel build
# machine's CPython and NumPy headers (/opt/python/cp3XY-cp3XY/...). Point them at this
# interpreter's headers (found by rosidl_generator_py) instead of editing the installed files.
# Against a real ROS 2 install no target names /opt/python/ and this changes nothing.
get_property(_imported_targets DIRECTORY PROPERTY IMPORTED_TARGETS)
foreach(_target IN LISTS _imported_targets)
  get_target_property(_dirs ${_target} INTERFACE_INCLUDE_DIRECTORIES)
  if(_dirs AND "${_dirs}" MATCHES "^/opt/python/|;/opt/python/")
    list(TRANSFORM _dirs REPLACE "^/opt/python/[^/]+/include/python3\\.[0-9]+$" "${Python3_INCLUDE_DIRS}")
    list(TRANSFORM _dirs REPLACE "^/opt/python/.*/numpy/_core/include$" "${Python3_NumPy_INCLUDE_DIRS}")
    set_target_properties(${_target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_dirs}")
  endif()
endforeach()
