# The dependency direction of src/ (src/README.md), checked from the `#include "..."` lines of every file in
# src/ (CTest Layout.IncludeDirection; Layout.FindsViolation runs it on violation/, a src/ that breaks it).
#   cmake -DSRC=<a src folder> -P tests/layout/check_includes.cmake
# An include of a src header names its folder ("pipeline/voxelize.h"); a file may include headers of its own
# folder and of the folders listed for it below, and the public API (deltagi/...) but the headers whose code
# is in a folder it may not include.
# Fails with one line per violation.
cmake_minimum_required(VERSION 3.22)

if(NOT DEFINED SRC)
  message(FATAL_ERROR "usage: cmake -DSRC=<src folder> -P check_includes.cmake")
endif()
get_filename_component(SRC "${SRC}" ABSOLUTE)

# Each folder and the other src folders it may include, lowest layer first.
set(allowed_io "")
set(allowed_core "")
set(allowed_pipeline core)
set(allowed_reference core pipeline)
set(allowed_scene core io)
set(allowed_loading core io pipeline reference scene)
set(allowed_evaluation core io pipeline reference scene loading)
set(allowed_live core io pipeline reference scene loading)
set(folders io core pipeline reference scene loading evaluation live)
# Public headers whose code is in one folder: a folder may include them only where it may include that
# folder.
set(api_folder_scene_io.h scene)
set(api_folder_albedo_estimation.h reference)
set(api_folder_reference.h reference)

set(violations "")
file(GLOB_RECURSE files RELATIVE ${SRC} ${SRC}/*.h ${SRC}/*.cpp)
if(NOT files)
  message(FATAL_ERROR "${SRC}: no .h or .cpp files")
endif()
foreach(file IN LISTS files)
  string(REGEX MATCH "^[^/]+/" folder "${file}")
  string(REPLACE "/" "" folder "${folder}")
  if(NOT folder IN_LIST folders)
    list(APPEND violations "${file}: not in one of the folders of src/README.md (${folders})")
    continue()
  endif()
  file(STRINGS ${SRC}/${file} includes REGEX "^[ \t]*#[ \t]*include[ \t]*\"")
  foreach(line IN LISTS includes)
    string(REGEX REPLACE "^[^\"]*\"([^\"]*)\".*$" "\\1" header "${line}")
    if(header MATCHES "^deltagi/")
      string(REPLACE "deltagi/" "" name "${header}")
      set(owner "${api_folder_${name}}")
      if(owner AND NOT owner STREQUAL folder AND NOT owner IN_LIST allowed_${folder})
        list(APPEND violations "${file} includes ${header}: its code is in ${owner}/, above ${folder}/")
      endif()
      continue()
    endif()
    string(REGEX MATCH "^[^/]+/" target "${header}")
    string(REPLACE "/" "" target "${target}")
    if(target STREQUAL "" OR NOT target IN_LIST folders)
      list(APPEND violations "${file} includes \"${header}\": name the header by its path from src/")
    elseif(NOT target STREQUAL folder AND NOT target IN_LIST allowed_${folder})
      list(APPEND violations "${file} includes ${header}: ${folder}/ may include only ${folder}/ ${allowed_${folder}}")
    elseif(NOT EXISTS ${SRC}/${header})
      list(APPEND violations "${file} includes ${header}, which is not there")
    endif()
  endforeach()
endforeach()

if(violations)
  list(LENGTH violations count)
  list(JOIN violations "\n  " text)
  message(FATAL_ERROR "src/ breaks its dependency direction (src/README.md), ${count} include(s):\n  ${text}")
endif()
list(LENGTH files count)
message(STATUS "${SRC}: ${count} files, every include one way")
