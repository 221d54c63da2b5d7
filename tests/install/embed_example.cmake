# CTest Install.EmbedExample: examples/embed configured, built and run as another project would, against the
# package installed in PREFIX (test Install.Prefix), never the build tree: deltagi_DIR points into PREFIX, and
# the consumer sees only PREFIX/include, so a public header that included anything of src/ would not compile.
#   cmake -DPREFIX=... -DSOURCE=examples/embed -DBUILD=... -P embed_example.cmake
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " command "${ARGN}")
    message(FATAL_ERROR "failed (${rc}): ${command}")
  endif()
endfunction()

file(REMOVE_RECURSE "${BUILD}")
run(${CMAKE_COMMAND} -S "${SOURCE}" -B "${BUILD}" -G Ninja -DCMAKE_BUILD_TYPE=Release
    "-Ddeltagi_DIR=${PREFIX}/lib/cmake/deltagi" "-DCMAKE_PREFIX_PATH=${PREFIX}")
run(${CMAKE_COMMAND} --build "${BUILD}")
run("${BUILD}/embed" "${BUILD}/embed.png")
if(NOT EXISTS "${BUILD}/embed.png")
  message(FATAL_ERROR "embed wrote no image")
endif()
