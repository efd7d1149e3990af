# CTest build.version (cmake -P): the one version source agrees everywhere.
#   -DHEADER=include/gearsim/version.h   -DPROJECT_VERSION=<project()>
#   -DPC_FILE=<build>/gearsim.pc          -DCONFIG_VERSION_FILE=<build>/gearsimConfigVersion.cmake
#   -DCONSUMER=<program printing "gs_version() = X">  (optional)
# Checks GS_VERSION_STRING = "MAJOR.MINOR.PATCH" of the same header = the
# CMake project version = the pkg-config Version = the CMake package version
# = what the built library's gs_version() returns. Fails naming the mismatch.
cmake_minimum_required(VERSION 3.16)

set(_failures "")
macro(_expect what value)
  if(NOT "${value}" STREQUAL "${_string}")
    list(APPEND _failures "${what} is '${value}', GS_VERSION_STRING is '${_string}'")
  endif()
  string(APPEND _report "\n  ${what}: ${value}")
endmacro()

include(${CMAKE_CURRENT_LIST_DIR}/gearsim_version.cmake)
gearsim_read_version("${HEADER}" _header_version)
set(_string "${_header_version_STRING}")
if(_string STREQUAL "")
  message(FATAL_ERROR "GS_VERSION_STRING not found in ${HEADER}")
endif()
set(_report "GS_VERSION_STRING (${HEADER}): ${_string}")
_expect("GS_VERSION_MAJOR.MINOR.PATCH" "${_header_version}")
_expect("CMake project version" "${PROJECT_VERSION}")

file(STRINGS "${PC_FILE}" _pc REGEX "^Version:")
string(REGEX REPLACE "^Version:[ \t]*" "" _pc "${_pc}")
_expect("gearsim.pc Version" "${_pc}")

file(STRINGS "${CONFIG_VERSION_FILE}" _cv REGEX "^set\\(PACKAGE_VERSION ")
string(REGEX REPLACE "^set\\(PACKAGE_VERSION \"([^\"]*)\"\\).*" "\\1" _cv "${_cv}")
_expect("gearsimConfigVersion.cmake" "${_cv}")

if(DEFINED CONSUMER)
  execute_process(COMMAND "${CONSUMER}" OUTPUT_VARIABLE _out ERROR_VARIABLE _err RESULT_VARIABLE _rc)
  if(NOT _rc EQUAL 0)
    list(APPEND _failures "${CONSUMER} exited ${_rc}: ${_out}${_err}")
  endif()
  if(_out MATCHES "gs_version\\(\\) = ([^ \t\r\n]+)")
    _expect("gs_version() of the built library" "${CMAKE_MATCH_1}")
  else()
    list(APPEND _failures "${CONSUMER} printed no 'gs_version() = ...' line: ${_out}${_err}")
  endif()
endif()

message("version: ${_report}")
if(_failures)
  list(JOIN _failures "\n  " _failures)
  message(FATAL_ERROR "version mismatch:\n  ${_failures}")
endif()
message("version: all agree on ${_string}")
