# The installed package (issue 14): `cmake --install build [--prefix P]` puts in place
#   P/lib/libdeltagi.so.0.1          the library (the pipeline, with Embree, TBB, Assimp, OpenEXR, libpng,
#                                    TurboJPEG, fmt, FFmpeg and AprilTag as its own private dependencies: a
#                                    consumer does not find or link them)
#   P/include/deltagi/*.h            the public API, which includes only the C++ library, GLM and nlohmann-json
#   P/lib/cmake/deltagi/             deltagiConfig.cmake: find_package(deltagi CONFIG) -> deltagi::deltagi
#   P/bin/deltagi                    the command line
#   P/lib/python3.X/dist-packages/   the Python module (python/CMakeLists.txt)
# A shared library, so that a consumer needs only GLM and nlohmann-json (the public headers use them) and not
# the packages the pipeline links; the command line and the tests link the same objects statically
# (deltagi_core), whose position-independent code costs nothing measurable on x86-64.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set_target_properties(deltagi_core PROPERTIES POSITION_INDEPENDENT_CODE ON)
# All its code is deltagi_core's objects; add_library needs one source of its own.
set(_shared_source ${PROJECT_BINARY_DIR}/generated/deltagi_shared.cpp)
file(CONFIGURE OUTPUT ${_shared_source} CONTENT "// libdeltagi.so: deltagi_core's objects (cmake/package.cmake).\n")
add_library(deltagi_shared SHARED ${_shared_source})
add_library(deltagi::deltagi ALIAS deltagi_shared)
# Every object of the archive, not only those the library's own (empty) sources would pull in.
target_link_libraries(deltagi_shared PRIVATE "$<LINK_LIBRARY:WHOLE_ARCHIVE,deltagi_core>")
target_link_libraries(deltagi_shared PUBLIC glm::glm nlohmann_json::nlohmann_json)
# Every symbol resolved when the library is linked, not when a consumer is (but under the sanitizers, whose
# runtime only executables link).
if(NOT DELTAGI_SANITIZE)
  target_link_options(deltagi_shared PRIVATE -Wl,--no-undefined)
endif()
target_include_directories(deltagi_shared PUBLIC
  $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
target_compile_definitions(deltagi_shared PUBLIC GLM_FORCE_XYZW_ONLY GLM_ENABLE_EXPERIMENTAL)
target_compile_features(deltagi_shared PUBLIC cxx_std_20)
# The ABI may change with every minor version while the version is 0.x.
set_target_properties(deltagi_shared PROPERTIES
  OUTPUT_NAME deltagi EXPORT_NAME deltagi LINKER_LANGUAGE CXX
  VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR})

install(TARGETS deltagi_shared EXPORT deltagiTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS deltagi RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY include/deltagi DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

set(DELTAGI_CMAKE_INSTALL_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/deltagi)
install(EXPORT deltagiTargets NAMESPACE deltagi:: DESTINATION ${DELTAGI_CMAKE_INSTALL_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/deltagiConfig.cmake.in
  ${PROJECT_BINARY_DIR}/deltagiConfig.cmake INSTALL_DESTINATION ${DELTAGI_CMAKE_INSTALL_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/deltagiConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/deltagiConfig.cmake ${PROJECT_BINARY_DIR}/deltagiConfigVersion.cmake
  DESTINATION ${DELTAGI_CMAKE_INSTALL_DIR})
