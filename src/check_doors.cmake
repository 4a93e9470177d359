# The one-way doors of the tree (docs/architecture.md): every `#include "..."` of a file in a room
# must name a file of the same room or of a room on a lower level. Rooms on one level do not
# include each other. A folder of src/ that is in no level fails too (a new room must be placed).
#   cmake -DROOT=<source dir> -P src/check_doors.cmake
# ctest runs it as include_doors, and include_doors_catches runs it on a planted wrong door.
#
# Levels, lowest first; a room is "src/<name>" or a top-level folder (models, solvers).
set(levels
  "src/core src/base src/paper src/parallel"
  "src/geometry"
  "models solvers"
  "src/measure src/render"
  "src/scene"
  "src/fit"
  "src/io"
  "src/repro"
  "src/cli src/python")

if(NOT ROOT)
  message(FATAL_ERROR "check_doors: -DROOT=<source dir> is required")
endif()
set(level_of_)
set(i 0)
foreach(level IN LISTS levels)
  string(REPLACE " " ";" rooms "${level}")
  foreach(room IN LISTS rooms)
    set(level_of_${room} ${i})
  endforeach()
  math(EXPR i "${i} + 1")
endforeach()

# Every folder of src/ must be a room.
file(GLOB children LIST_DIRECTORIES true RELATIVE ${ROOT} ${ROOT}/src/*)
set(bad "")
foreach(child IN LISTS children)
  if(IS_DIRECTORY ${ROOT}/${child} AND NOT DEFINED level_of_${child})
    list(APPEND bad "${child}/: a folder of src/ that is no room (add it to a level in src/check_doors.cmake)")
  endif()
endforeach()

file(GLOB_RECURSE sources RELATIVE ${ROOT}
  ${ROOT}/src/*.hpp ${ROOT}/src/*.cpp ${ROOT}/models/*.hpp ${ROOT}/models/*.cpp
  ${ROOT}/solvers/*.hpp ${ROOT}/solvers/*.cpp)
foreach(file IN LISTS sources)
  string(REGEX MATCH "^(src/[^/]+|models|solvers)/" from "${file}")
  string(REGEX REPLACE "/$" "" from "${from}")
  if(NOT DEFINED level_of_${from})
    list(APPEND bad "${file}: in no room (a source file belongs in a folder of src/)")
    continue()
  endif()
  file(STRINGS ${ROOT}/${file} includes REGEX "^[ \t]*#[ \t]*include[ \t]+\"")
  foreach(line IN LISTS includes)
    string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]+\"([^\"]+)\".*" "\\1" target "${line}")
    string(REGEX MATCH "^(src/[^/]+|models|solvers)/" to "${target}")
    string(REGEX REPLACE "/$" "" to "${to}")
    if(to STREQUAL "" OR to STREQUAL from)
      continue()  # a generated header (knitsim_git_commit.hpp) or the same room
    endif()
    if(NOT DEFINED level_of_${to})
      list(APPEND bad "${file}: includes ${target}, in no room")
    elseif(NOT level_of_${to} LESS level_of_${from})
      list(APPEND bad "${file}: includes ${target} (${to} is not below ${from})")
    endif()
  endforeach()
endforeach()

if(bad)
  list(LENGTH bad n)
  string(REPLACE ";" "\n  " text "${bad}")
  message(FATAL_ERROR "check_doors: ${n} door(s) the wrong way:\n  ${text}")
endif()
list(LENGTH sources n)
message(STATUS "check_doors: ${n} files, every include points down")
