# Runs a command and checks its exit status, its output and the files it leaves; used by the
# end-to-end tests of `bagsim run` (tests/app/CMakeLists.txt).
#
#   cmake -DEXPECT_RC=N [-DEXPECT_REGEX=RE] [-DCLEAN_DIR=D] [-DNONEMPTY_DIR=D]
#         [-DEXPECT_FILES="a;b"] [-DEXPECT_ABSENT="c;d"] [-DEXPECT_FIRST_LINES="f=line|g=line"]
#         -P ExpectRun.cmake -- COMMAND ARGS...
#
# EXPECT_REGEX is matched against stdout + stderr. CLEAN_DIR is removed before the run;
# NONEMPTY_DIR is created with a file in it before the run. EXPECT_FILES must exist and
# EXPECT_ABSENT must not after it. EXPECT_FIRST_LINES: file=exact first line, '|'-separated.

set(cmd "")
set(after FALSE)
math(EXPR last "${CMAKE_ARGC} - 1")
foreach(i RANGE ${last})
  if(after)
    list(APPEND cmd "${CMAKE_ARGV${i}}")
  elseif("${CMAKE_ARGV${i}}" STREQUAL "--")
    set(after TRUE)
  endif()
endforeach()
if(NOT cmd)
  message(FATAL_ERROR "ExpectRun: no command after --")
endif()

if(DEFINED CLEAN_DIR)
  file(REMOVE_RECURSE "${CLEAN_DIR}")
endif()
if(DEFINED NONEMPTY_DIR)
  file(REMOVE_RECURSE "${NONEMPTY_DIR}")
  file(WRITE "${NONEMPTY_DIR}/earlier-results.txt" "not to be overwritten\n")
endif()

execute_process(COMMAND ${cmd} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
set(all "${out}${err}")
message("${all}")

if(NOT "${rc}" STREQUAL "${EXPECT_RC}")
  message(FATAL_ERROR "exit status ${rc}, expected ${EXPECT_RC}")
endif()
if(DEFINED EXPECT_REGEX AND NOT all MATCHES "${EXPECT_REGEX}")
  message(FATAL_ERROR "output does not match: ${EXPECT_REGEX}")
endif()
foreach(f IN LISTS EXPECT_FILES)
  if(NOT EXISTS "${f}")
    message(FATAL_ERROR "missing: ${f}")
  endif()
endforeach()
foreach(f IN LISTS EXPECT_ABSENT)
  if(EXISTS "${f}")
    message(FATAL_ERROR "should not exist: ${f}")
  endif()
endforeach()
if(DEFINED EXPECT_FIRST_LINES)
  string(REPLACE "|" ";" pairs "${EXPECT_FIRST_LINES}")
  foreach(pair IN LISTS pairs)
    string(FIND "${pair}" "=" eq)
    string(SUBSTRING "${pair}" 0 ${eq} f)
    math(EXPR start "${eq} + 1")
    string(SUBSTRING "${pair}" ${start} -1 expected)
    file(STRINGS "${f}" lines LIMIT_COUNT 1)
    if(NOT "${lines}" STREQUAL "${expected}")
      message(FATAL_ERROR "${f}: first line '${lines}', expected '${expected}'")
    endif()
  endforeach()
endif()
