# CTest Install.EmbedExample: examples/embed configured, built and run as another project would, against the
# package installed in PREFIX (test Install.Prefix), never the build tree: deltagi_DIR points into PREFIX, and
# the consumer sees only PREFIX/include, so a public header that included anything of src/ would not compile:
# every installed header is compiled too, in a second project beside it.
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
run(${CMAKE_COMMAND} --build "${BUILD}" -j 2)
run("${BUILD}/embed" "${BUILD}/embed.png")
if(NOT EXISTS "${BUILD}/embed.png")
  message(FATAL_ERROR "embed wrote no image")
endif()

# Every public header, each included first in its own translation unit (self-contained, nothing of src/).
set(headers_project "${BUILD}-headers")
file(REMOVE_RECURSE "${headers_project}")
file(GLOB headers RELATIVE "${PREFIX}/include" "${PREFIX}/include/deltagi/*.h")
set(sources)
foreach(header IN LISTS headers)
  string(MAKE_C_IDENTIFIER "${header}" name)
  file(WRITE "${headers_project}/${name}.cpp" "#include \"${header}\"\n")
  list(APPEND sources "${name}.cpp")
endforeach()
file(WRITE "${headers_project}/CMakeLists.txt" "cmake_minimum_required(VERSION 3.22)
project(deltagi_headers LANGUAGES CXX)
find_package(deltagi CONFIG REQUIRED)
add_library(headers OBJECT ${sources})
target_link_libraries(headers PRIVATE deltagi::deltagi)
")
run(${CMAKE_COMMAND} -S "${headers_project}" -B "${headers_project}/build" -G Ninja
    "-Ddeltagi_DIR=${PREFIX}/lib/cmake/deltagi")
run(${CMAKE_COMMAND} --build "${headers_project}/build" -j 2)
