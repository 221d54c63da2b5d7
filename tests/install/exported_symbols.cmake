# libdeltagi.so exports the API of include/deltagi/ and nothing of the library's inside (deltagi/export.h):
#   cmake -DLIBRARY=<libdeltagi.so> -P tests/install/exported_symbols.cmake
# Fails naming an internal symbol that is exported, or a public one that is not.
execute_process(COMMAND nm -D --defined-only -C "${LIBRARY}" OUTPUT_VARIABLE symbols RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "nm -D ${LIBRARY} failed (${result})")
endif()
set(failures "")
foreach(public IN ITEMS "deltagi::render(" "deltagi::FrameRenderer::render(" "deltagi::loadScene("
                        "deltagi::writeImage(" "deltagi::makeSphere(" "typeinfo for deltagi::InputError")
  string(FIND "${symbols}" "${public}" at)
  if(at EQUAL -1)
    list(APPEND failures "public ${public} is not exported")
  endif()
endforeach()
# The pipeline's stages, the ray casting, the frame cache, the path tracer and the command line's helpers.
foreach(internal IN ITEMS "deltagi::voxelize(" "deltagi::injectLight(" "deltagi::RayScene::" "deltagi::FrameCache::"
                          "deltagi::PathTracer::" "deltagi::AtomicFile::" "deltagi::runBenchmark(" "deltagi::traceCones(")
  string(FIND "${symbols}" "${internal}" at)
  if(NOT at EQUAL -1)
    list(APPEND failures "internal ${internal} is exported")
  endif()
endforeach()
if(failures)
  list(JOIN failures "\n  " text)
  message(FATAL_ERROR "${LIBRARY}:\n  ${text}")
endif()
string(REGEX MATCHALL "deltagi::" all "${symbols}")
list(LENGTH all count)
message(STATUS "${LIBRARY}: exports the public API only (${count} deltagi symbols)")
