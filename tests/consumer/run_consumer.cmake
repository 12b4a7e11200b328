# ctest driver (tests/CMakeLists.txt): install the build into a prefix, move the prefix (the
# package must be relocatable), configure tests/consumer against it, build, run its tests,
# compile the same program through pkg-config, and import the Python module from the prefix.
# -D: BUILD_DIR, SOURCE_DIR (tests/consumer), WORK_DIR, GENERATOR, CXX, PYTHON.
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  message(STATUS "$ ${ARGN}\n${out}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}")
  endif()
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/staging)
file(RENAME ${WORK_DIR}/staging ${WORK_DIR}/prefix)
set(P ${WORK_DIR}/prefix)
foreach(f bin/scatterlab include/scatterlab/scatterlab.h include/scatterlab/api/scatterlab.h share/scatterlab/plots.py)
  if(NOT EXISTS ${P}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()

# The installed headers include each other as <scatterlab/…> only (cmake/install_headers.cmake):
# none by the source tree's quoted "core/…" paths, which a consumer's own headers could shadow.
file(GLOB_RECURSE installed_headers ${P}/include/scatterlab/*.h)
foreach(h IN LISTS installed_headers)
  file(STRINGS ${h} quoted REGEX "#include \"(api|core|cpu|experiment|gpu|media|methods|sampling|shading)/")
  if(quoted)
    message(FATAL_ERROR "${h} includes a scatterlab header by a quoted path: ${quoted}")
  endif()
endforeach()

# Every scene of the source tree is installed and loads from the moved prefix (the installed
# tool parses it, reads its files, VDB volumes and meshes included, and validates its method).
file(GLOB installed_scenes ${P}/share/scatterlab/scenes/*.json)
file(GLOB source_scenes ${SOURCE_DIR}/../../data/scenes/*.json)
list(LENGTH installed_scenes n_installed)
if(n_installed EQUAL 0)
  message(FATAL_ERROR "no scene installed under ${P}/share/scatterlab/scenes")
endif()
foreach(src IN LISTS source_scenes)
  get_filename_component(name ${src} NAME)
  if(NOT EXISTS ${P}/share/scatterlab/scenes/${name})
    message(FATAL_ERROR "data/scenes/${name} is not installed")
  endif()
endforeach()
foreach(scene IN LISTS installed_scenes)
  run(${P}/bin/scatterlab info ${scene})
endforeach()
message(STATUS "${n_installed} installed scenes load from the prefix")

run(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -G ${GENERATOR}
    -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${P})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${CMAKE_CTEST_COMMAND} --test-dir ${WORK_DIR}/build --output-on-failure)

# pkg-config: the same program, compiled and linked with the flags of scatterlab.pc.
file(GLOB pcdir ${P}/lib*/pkgconfig ${P}/lib/*/pkgconfig)
execute_process(COMMAND ${CMAKE_COMMAND} -E env PKG_CONFIG_PATH=${pcdir}
                pkg-config --cflags --libs scatterlab
                OUTPUT_VARIABLE flags RESULT_VARIABLE rc OUTPUT_STRIP_TRAILING_WHITESPACE)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "pkg-config --cflags --libs scatterlab failed")
endif()
separate_arguments(flags UNIX_COMMAND "${flags}")
# No -std here: the .pc's Cflags must carry it (g++ 12 defaults to C++17).
run(${CXX} -O1 -I${SOURCE_DIR} ${SOURCE_DIR}/main.cpp -o ${WORK_DIR}/consumer_pc ${flags})
run(${WORK_DIR}/consumer_pc)

# Python: the module from the prefix, one PYTHONPATH.
file(GLOB pydir ${P}/lib/python3*/dist-packages ${P}/lib/python3*/site-packages)
if(PYTHON)
  run(${CMAKE_COMMAND} -E env PYTHONPATH=${pydir} ${PYTHON} -c
      "import scatterlab as sl; print(sl.__file__, sl.__version__); assert sl.__version__.startswith('0.2')")
endif()
