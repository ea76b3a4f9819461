# Run at build time (cmake -P) after a test binary links: lists its GoogleTest suites and writes
# one ctest test per suite (`BINARY --gtest_filter=Suite.*`) into OUTPUT, which ctest includes.
# One process per suite instead of per test: each process start loads the ~260 shared libraries
# that OpenImageIO and OpenCV's videoio pull in (0.4 s, twice that under the sanitizers).
# Inputs (-D): EXECUTABLE, OUTPUT, WORKING_DIRECTORY, LABEL, EXCLUDE (a regular expression over
# suite names; "" excludes none), WEIGHT (ctest COST per test of a suite: the longest-looking
# suites start first), TIMEOUT (seconds for the listing).
execute_process(COMMAND "${EXECUTABLE}" --gtest_list_tests
                WORKING_DIRECTORY "${WORKING_DIRECTORY}"
                OUTPUT_VARIABLE listing ERROR_VARIABLE errors RESULT_VARIABLE result TIMEOUT ${TIMEOUT})
if(NOT result EQUAL 0)
  message(FATAL_ERROR "${EXECUTABLE} --gtest_list_tests failed (${result}):\n${listing}${errors}")
endif()

string(REPLACE ";" "\\;" listing "${listing}")
string(REPLACE "\n" ";" lines "${listing}")
set(suites)
foreach(line IN LISTS lines)
  if(line MATCHES "^([^ #][^ ]*)\\.( .*)?$")  # "Suite." or "Prefix/Suite.  # TypeParam = ..."
    set(suite "${CMAKE_MATCH_1}")
    list(APPEND suites "${suite}")
    set(count_${suite} 0)
  elseif(line MATCHES "^  [^ ]" AND suite)
    math(EXPR count_${suite} "${count_${suite}} + 1")
  endif()
endforeach()

set(text "# Written by cmake/list_gtest_suites.cmake from ${EXECUTABLE} --gtest_list_tests\n")
foreach(suite IN LISTS suites)
  if(NOT EXCLUDE STREQUAL "" AND suite MATCHES "${EXCLUDE}")
    continue()
  endif()
  math(EXPR cost "${count_${suite}} * ${WEIGHT}")
  # A suite whose every test skipped (data absent) is reported as skipped, not passed.
  string(APPEND text
    "add_test([==[${suite}]==] [==[${EXECUTABLE}]==] [==[--gtest_filter=${suite}.*]==])\n"
    "set_tests_properties([==[${suite}]==] PROPERTIES WORKING_DIRECTORY [==[${WORKING_DIRECTORY}]==] "
    "LABELS [==[${LABEL}]==] COST ${cost} SKIP_REGULAR_EXPRESSION [==[\\[  PASSED  \\] 0 tests\\.]==])\n")
endforeach()
file(WRITE "${OUTPUT}" "${text}")
