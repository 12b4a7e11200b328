# Run at install time (install(CODE) in cmake/install.cmake): installs the headers under
# include/scatterlab/ with every include of another scatterlab header written as
# #include <scatterlab/MODULE/…> instead of the source tree's #include "MODULE/…", as OpenVDB's
# <openvdb/…>. Only include/ is then on a consumer's path, and an engine's own core/scene.h or
# gpu/context.h cannot be taken for ours (issue 36; tests/consumer has such a header).
# In: SCATTERLAB_SOURCE_DIR, SCATTERLAB_STAGE_DIR (a folder of the build tree),
# SCATTERLAB_HEADER_MODULES (the installed modules), SCATTERLAB_INCLUDE_DEST (relative to the
# prefix). file(INSTALL) honours DESTDIR and lists each file as the other install rules do.
file(REMOVE_RECURSE "${SCATTERLAB_STAGE_DIR}")
list(JOIN SCATTERLAB_HEADER_MODULES "|" modules)
set(headers scatterlab.h)
foreach(m IN LISTS SCATTERLAB_HEADER_MODULES)
  file(GLOB_RECURSE hs RELATIVE "${SCATTERLAB_SOURCE_DIR}" "${SCATTERLAB_SOURCE_DIR}/${m}/*.h")
  list(FILTER hs EXCLUDE REGEX "/shaders/")
  list(APPEND headers ${hs})
endforeach()
foreach(h IN LISTS headers)
  file(READ "${SCATTERLAB_SOURCE_DIR}/${h}" text)
  string(REGEX REPLACE "#include \"((${modules})/[^\"]+)\"" "#include <scatterlab/\\1>" text
         "${text}")
  if(text MATCHES "#include \"(${modules})/")
    message(FATAL_ERROR "install: ${h} still includes a scatterlab header by a quoted path")
  endif()
  file(WRITE "${SCATTERLAB_STAGE_DIR}/scatterlab/${h}" "${text}")
  get_filename_component(dir "${h}" DIRECTORY)
  file(INSTALL "${SCATTERLAB_STAGE_DIR}/scatterlab/${h}"
       DESTINATION "${CMAKE_INSTALL_PREFIX}/${SCATTERLAB_INCLUDE_DEST}/scatterlab/${dir}")
endforeach()
