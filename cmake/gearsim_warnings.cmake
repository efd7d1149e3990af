# gearsim_read_warnings(<out_var> [WERROR <bool>]): the library's C warning
# set, read from cmake/gearsim_warnings.txt (one flag per line, # comments;
# the Python extension build reads the same file), plus -Werror when WERROR is
# true. Empty for compilers other than GCC and Clang. Re-configures when the
# file changes.
set(_GEARSIM_WARNINGS_FILE "${CMAKE_CURRENT_LIST_DIR}/gearsim_warnings.txt")

function(gearsim_read_warnings out_var)
  cmake_parse_arguments(PARSE_ARGV 1 _arg "" "WERROR" "")
  set(_flags "")
  if(CMAKE_C_COMPILER_ID MATCHES "GNU|Clang")
    file(STRINGS "${_GEARSIM_WARNINGS_FILE}" _lines)
    foreach(_line IN LISTS _lines)
      string(STRIP "${_line}" _line)
      if(_line STREQUAL "" OR _line MATCHES "^#")
        continue()
      endif()
      list(APPEND _flags "${_line}")
    endforeach()
    if(NOT _flags)
      message(FATAL_ERROR "gearsim: no warning flag in ${_GEARSIM_WARNINGS_FILE}")
    endif()
    if(_arg_WERROR)
      list(APPEND _flags -Werror)
    endif()
  endif()
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${_GEARSIM_WARNINGS_FILE}")
  set(${out_var} "${_flags}" PARENT_SCOPE)
endfunction()
