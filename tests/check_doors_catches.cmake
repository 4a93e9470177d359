# The door check must fail on a door the wrong way: a copy of the tree with one planted include
# (the core including the command line) and one planted folder that is no room.
#   cmake -DROOT=<source dir> -DWORK=<scratch dir> -P tests/check_doors_catches.cmake
file(REMOVE_RECURSE ${WORK})
foreach(dir src models solvers)
  file(COPY ${ROOT}/${dir} DESTINATION ${WORK} FILES_MATCHING PATTERN "*.hpp" PATTERN "*.cpp")
endforeach()
file(COPY ${ROOT}/src/check_doors.cmake DESTINATION ${WORK}/src)
execute_process(COMMAND ${CMAKE_COMMAND} -DROOT=${WORK} -P ${WORK}/src/check_doors.cmake
                RESULT_VARIABLE clean_rc OUTPUT_QUIET ERROR_QUIET)
if(NOT clean_rc EQUAL 0)
  message(FATAL_ERROR "the unchanged copy fails the check (rc ${clean_rc})")
endif()

macro(expect_caught what needle)
  execute_process(COMMAND ${CMAKE_COMMAND} -DROOT=${WORK} -P ${WORK}/src/check_doors.cmake
                  RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
  string(FIND "${err}" "${needle}" at)
  if(rc EQUAL 0 OR at EQUAL -1)
    message(FATAL_ERROR "${what} was not caught (rc ${rc}): ${err}")
  endif()
endmacro()

file(APPEND ${WORK}/src/core/sparse.cpp "\n#include \"src/cli/commands.hpp\"\n")
expect_caught("core including cli" "src/core/sparse.cpp: includes src/cli/commands.hpp")
file(COPY ${ROOT}/src/core/sparse.cpp DESTINATION ${WORK}/src/core)

file(APPEND ${WORK}/src/render/plot.cpp "\n#include \"src/measure/measurement.hpp\"\n")  # a sibling on one level
expect_caught("render including measure" "src/render/plot.cpp: includes src/measure/measurement.hpp")
file(COPY ${ROOT}/src/render/plot.cpp DESTINATION ${WORK}/src/render)

file(MAKE_DIRECTORY ${WORK}/src/attic)
expect_caught("a folder that is no room" "src/attic/: a folder of src/ that is no room")
message(STATUS "check_doors catches a planted wrong door, a sibling door and a stray folder")
