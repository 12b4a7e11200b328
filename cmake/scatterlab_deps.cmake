# Locating OpenVDB's find module, shared by the build (CMakeLists.txt) and the installed
# package (scatterlabConfig.cmake). OpenVDB installs FindOpenVDB.cmake (no config file) under
# <prefix>/lib[/<arch>]/cmake/OpenVDB; this looks there under CMAKE_PREFIX_PATH and the system
# prefixes instead of naming one distribution's directory. A FindOpenVDB.cmake already on the
# CMAKE_MODULE_PATH, or -DSCATTERLAB_OPENVDB_MODULE_DIR=DIR, wins.
macro(scatterlab_find_openvdb_module)
  set(_scatterlab_have_vdb_module FALSE)
  foreach(_dir IN LISTS CMAKE_MODULE_PATH)
    if(EXISTS "${_dir}/FindOpenVDB.cmake")
      set(_scatterlab_have_vdb_module TRUE)
    endif()
  endforeach()
  if(NOT _scatterlab_have_vdb_module)
    set(_scatterlab_vdb_candidates)
    foreach(_prefix IN LISTS CMAKE_PREFIX_PATH CMAKE_SYSTEM_PREFIX_PATH)
      list(APPEND _scatterlab_vdb_candidates
           "${_prefix}/lib/${CMAKE_LIBRARY_ARCHITECTURE}/cmake/OpenVDB"
           "${_prefix}/lib64/cmake/OpenVDB" "${_prefix}/lib/cmake/OpenVDB")
    endforeach()
    find_path(SCATTERLAB_OPENVDB_MODULE_DIR FindOpenVDB.cmake
              PATHS ${_scatterlab_vdb_candidates} NO_DEFAULT_PATH
              DOC "Directory holding OpenVDB's FindOpenVDB.cmake")
    if(SCATTERLAB_OPENVDB_MODULE_DIR)
      list(APPEND CMAKE_MODULE_PATH "${SCATTERLAB_OPENVDB_MODULE_DIR}")
    endif()
  endif()
endmacro()

# find_package at warning level: Debian's FindOpenVDB.cmake prints "COMPONENT = openvdb" and
# Imath's targets file (found through OpenEXR) names a Python binding library that Debian does
# not ship and scatterlab does not use; neither is news to whoever builds scatterlab.
macro(scatterlab_find_package_quietly)
  set(_scatterlab_log_level "${CMAKE_MESSAGE_LOG_LEVEL}")
  set(CMAKE_MESSAGE_LOG_LEVEL WARNING)
  find_package(${ARGN})
  set(CMAKE_MESSAGE_LOG_LEVEL "${_scatterlab_log_level}")
endmacro()
