# A knitsim binary names none of the heavy libraries among its NEEDED entries (the shared
# libraries the dynamic loader maps at every start; docs/architecture.md): not MPI (a module
# loaded under mpirun), not cairo, a BLAS, METIS nor libgomp (loaded on first use), not
# SUNDIALS, SuiteSparse or toml++ (linked statically or compiled in). Anything they need comes
# in through them, so the binary's own list decides. With -DSTATIC_CXX_RUNTIME=ON (knitsim
# built by GCC without a sanitizer links the C++ runtime statically, src/CMakeLists.txt)
# libstdc++ and libgcc_s are not allowed either.
#   cmake -DEXE=<binary> -DOBJDUMP=<objdump> [-DSTATIC_CXX_RUNTIME=ON]
#         -P tests/check_startup_libraries.cmake
# ctest runs it on knitsim as startup_libraries, and startup_libraries_catches runs it on the MPI
# module (which does link libmpi), expecting it to fail.
if(NOT EXE OR NOT OBJDUMP)
  message(FATAL_ERROR "check_startup_libraries: -DEXE=<binary> -DOBJDUMP=<objdump> are required")
endif()
execute_process(COMMAND ${OBJDUMP} -p ${EXE} OUTPUT_VARIABLE dump RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "check_startup_libraries: ${OBJDUMP} -p ${EXE} failed (${status})")
endif()
string(REGEX MATCHALL "NEEDED +[^\n]+" needed "${dump}")
if(NOT needed)
  message(FATAL_ERROR "check_startup_libraries: no NEEDED entry in ${EXE} (not a dynamic ELF?)")
endif()
set(heavy "libmpi|libopen-rte|libopen-pal|libhwloc|libcairo|libblas|liblapack|libopenblas|"
          "libgfortran|libsundials|libcholmod|libklu|libtomlplusplus|libmetis|libgomp")
string(CONCAT heavy ${heavy})
if(STATIC_CXX_RUNTIME)
  string(APPEND heavy "|libstdc\\+\\+|libgcc_s")
endif()
set(bad "")
set(names "")
foreach(entry IN LISTS needed)
  string(REGEX REPLACE "NEEDED +" "" library "${entry}")
  list(APPEND names "${library}")
  if(library MATCHES "^(${heavy})")
    list(APPEND bad "${library}")
  endif()
endforeach()
if(bad)
  string(REPLACE ";" ", " bad "${bad}")
  message(FATAL_ERROR "${EXE} links ${bad} at start-up; see docs/architecture.md (a run maps "
                      "only the libraries it uses)")
endif()
string(REPLACE ";" ", " names "${names}")
message(STATUS "${EXE} needs ${names}")
