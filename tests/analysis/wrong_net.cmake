# Runs `tripodal-net check` on one net of the corpus of wrong nets (tests/data/nets/wrong/) and
# compares with what the file's header comment expects:
#   expect-exit: N        the exit status
#   expect-args: A B      extra arguments for check, separated by spaces (optional); @DIR@ is
#                         the net's directory
#   expect: REGEX         the output (stdout and stderr) must match, one line per key part of the
#                         message; no ';' (CMake would split the line): write '.' for it
# Usage: cmake -DTOOL=tripodal-net -DNET=file.xml -P wrong_net.cmake
file(READ "${NET}" text)
if(text MATCHES "expect[^\n]*;")
  message(FATAL_ERROR "${NET}: an expect line holds ';', which CMake splits: write '.' instead")
endif()
file(STRINGS "${NET}" header REGEX "^ *expect(-exit|-args)?: ")
set(exit_expected "")
set(args "")
set(patterns "")
foreach(line IN LISTS header)
  string(STRIP "${line}" line)
  if(line MATCHES "^expect-exit: *([0-9]+)$")
    set(exit_expected "${CMAKE_MATCH_1}")
  elseif(line MATCHES "^expect-args: *(.*)$")
    set(args "${CMAKE_MATCH_1}")
  elseif(line MATCHES "^expect: *(.*)$")
    list(APPEND patterns "${CMAKE_MATCH_1}")
  endif()
endforeach()
if(exit_expected STREQUAL "" OR NOT patterns)
  message(FATAL_ERROR "${NET}: the header needs 'expect-exit: N' and at least one 'expect: REGEX' line")
endif()
get_filename_component(dir "${NET}" DIRECTORY)
string(REPLACE "@DIR@" "${dir}" args "${args}")
separate_arguments(args UNIX_COMMAND "${args}")
execute_process(COMMAND "${TOOL}" check "${NET}" ${args} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
set(all "${out}${err}")
message("${all}")
if(NOT rc STREQUAL exit_expected)
  message(FATAL_ERROR "${NET}: exit status ${rc}, expected ${exit_expected}")
endif()
foreach(p IN LISTS patterns)
  if(NOT all MATCHES "${p}")
    message(FATAL_ERROR "${NET}: no match for '${p}'")
  endif()
endforeach()
