# Install rules and the CMake package (find_package(scatterlab 0.2)), a pkg-config file, the
# tool, the headers under include/scatterlab/ (included as <scatterlab/…>) and the Python helper scripts under
# share/scatterlab/. Every installed path is relative to the prefix (relocatable).
include(CMakePackageConfigHelpers)

set(SCATTERLAB_CMAKE_INSTALL_DIR "${CMAKE_INSTALL_LIBDIR}/cmake/scatterlab")
set(SCATTERLAB_DATA_INSTALL_DIR "${CMAKE_INSTALL_DATADIR}/scatterlab")

# Static libraries, dependency order (a linker reading pkg-config's list needs it).
set(_libs scatterlab scatterlab_experiment scatterlab_methods)
set(_modules api experiment methods)
if(TARGET scatterlab_gpu)
  list(APPEND _libs scatterlab_gpu)
  list(APPEND _modules gpu)
endif()
list(APPEND _libs scatterlab_cpu scatterlab_sampling scatterlab_shading scatterlab_media scatterlab_core)
list(APPEND _modules cpu sampling shading media core)

foreach(_lib IN LISTS _libs)
  if(NOT _lib STREQUAL "scatterlab")
    string(REPLACE "scatterlab_" "" _short ${_lib})
    set_target_properties(${_lib} PROPERTIES EXPORT_NAME ${_short})  # scatterlab::core, ...
  endif()
endforeach()
set_target_properties(scatterlab_cli PROPERTIES EXPORT_NAME tool)  # scatterlab::tool

install(TARGETS ${_libs} EXPORT scatterlabTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS scatterlab_cli EXPORT scatterlabTargets RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# The VDB reader program, where the library looks for it relative to bin/ and the Python package.
install(TARGETS scatterlab_vdb_reader RUNTIME DESTINATION ${CMAKE_INSTALL_LIBEXECDIR}/scatterlab)
# The headers, the top-level <scatterlab/scatterlab.h> (it forwards to api/scatterlab.h) and
# every module's, each including the others as <scatterlab/MODULE/…> (cmake/install_headers.cmake):
# only include/ goes on a consumer's path.
install(CODE "
  set(SCATTERLAB_SOURCE_DIR \"${PROJECT_SOURCE_DIR}\")
  set(SCATTERLAB_STAGE_DIR \"${PROJECT_BINARY_DIR}/installed-headers\")
  set(SCATTERLAB_HEADER_MODULES \"${_modules}\")
  set(SCATTERLAB_INCLUDE_DEST \"${CMAKE_INSTALL_INCLUDEDIR}\")
  include(\"${PROJECT_SOURCE_DIR}/cmake/install_headers.cmake\")")
install(FILES ${PROJECT_SOURCE_DIR}/experiment/plots.py ${PROJECT_SOURCE_DIR}/scripts/results_md.py
        DESTINATION ${SCATTERLAB_DATA_INSTALL_DIR})
# The demo scenes with the data they read beside them (data/vdb, data/meshes; sources and
# licences in their .txt sidecars and the README), so that every installed scene loads from the
# prefix (tests/consumer).
install(DIRECTORY ${PROJECT_SOURCE_DIR}/data/scenes DESTINATION ${SCATTERLAB_DATA_INSTALL_DIR}
        FILES_MATCHING PATTERN "*.json" PATTERN "*.f32")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/data/vdb DESTINATION ${SCATTERLAB_DATA_INSTALL_DIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/data/meshes DESTINATION ${SCATTERLAB_DATA_INSTALL_DIR})

install(EXPORT scatterlabTargets NAMESPACE scatterlab:: DESTINATION ${SCATTERLAB_CMAKE_INSTALL_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/scatterlabConfig.cmake.in
  ${PROJECT_BINARY_DIR}/scatterlabConfig.cmake
  INSTALL_DESTINATION ${SCATTERLAB_CMAKE_INSTALL_DIR}
  PATH_VARS CMAKE_INSTALL_INCLUDEDIR SCATTERLAB_DATA_INSTALL_DIR)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/scatterlabConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/scatterlabConfig.cmake
              ${PROJECT_BINARY_DIR}/scatterlabConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/scatterlab_deps.cmake
        DESTINATION ${SCATTERLAB_CMAKE_INSTALL_DIR})

# pkg-config: static libraries, so every one is listed (dependency order) with what they need;
# Cflags carry -std=c++20 (scatterlab.pc.in), the headers' language, as the CMake targets do.
set(SCATTERLAB_PC_LIBS "")
foreach(_lib IN LISTS _libs)
  string(APPEND SCATTERLAB_PC_LIBS " -l${_lib}")
endforeach()
string(STRIP "${SCATTERLAB_PC_LIBS}" SCATTERLAB_PC_LIBS)
set(SCATTERLAB_PC_GPU_REQUIRES "")
set(SCATTERLAB_PC_CFLAGS "")
if(TARGET scatterlab_gpu)
  set(SCATTERLAB_PC_GPU_REQUIRES " epoxy egl")
  set(SCATTERLAB_PC_CFLAGS " -DSCATTERLAB_HAS_GPU=1")
endif()
configure_file(${PROJECT_SOURCE_DIR}/cmake/scatterlab.pc.in ${PROJECT_BINARY_DIR}/scatterlab.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/scatterlab.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
