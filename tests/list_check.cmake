# CTest test <program>.listed (tests/CMakeLists.txt): the tests a program
# has (--gtest_list_tests) are exactly those its sources were scanned for at
# configure time (EXPECTED: --gtest_filter patterns, */Suite.Test/* for a
# TEST_P's instantiations). A test the scan missed would never run, and a
# name it made up would run nothing.
#   cmake -DPROGRAM=<test program> -DEXPECTED=<file> -P list_check.cmake
execute_process(COMMAND ${PROGRAM} --gtest_list_tests OUTPUT_VARIABLE listing RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${PROGRAM} --gtest_list_tests exited with ${rc}")
endif()
# "Suite.\n  Test\n", "Instance/Suite.\n  Test/Param  # GetParam() = ...\n"
string(REPLACE "\n" ";" lines "${listing}")
set(have)
foreach(line ${lines})
  if(line MATCHES "^([A-Za-z_0-9/]+)\\.")
    set(suite ${CMAKE_MATCH_1})
  elseif(line MATCHES "^  ([A-Za-z_0-9]+)(/[^ ]*)?")
    set(test ${CMAKE_MATCH_1}) # (the next MATCHES resets CMAKE_MATCH_1)
    if(suite MATCHES "/")
      string(REGEX REPLACE "^[^/]*/" "" bare ${suite})
      list(APPEND have "*/${bare}.${test}/*")
    else()
      list(APPEND have "${suite}.${test}")
    endif()
  endif()
endforeach()
list(REMOVE_DUPLICATES have)
file(READ ${EXPECTED} expected)
set(missing ${have})
list(REMOVE_ITEM missing ${expected})
set(invented ${expected})
list(REMOVE_ITEM invented ${have})
if(missing OR invented)
  message(FATAL_ERROR "${PROGRAM}: tests the sources' scan did not find: ${missing}; "
                      "found but not in the program: ${invented} (tests/CMakeLists.txt, isoscope_tests_in)")
endif()
list(LENGTH have n)
message(STATUS "${PROGRAM}: ${n} tests, as the sources list them")
