# SPDX-License-Identifier: Apache-2.0
# check_no_malloc.cmake - fail if a library (libtrn.a, libtrn_proto.a) references a heap allocator.
#
# The core never allocates (docs/architecture.md, "Fixed memory"). This script
# proves it mechanically: it lists the undefined symbols of every object in the
# static library with the target's own nm and fails on any allocator.
#
#   cmake -DNM=<nm> -DLIB=<libtrn.a> -P check_no_malloc.cmake
#
# Used by the `no_malloc` CTest test and by the bare-metal build's post-build
# report.

if(NOT NM OR NOT LIB)
  message(FATAL_ERROR "usage: cmake -DNM=<nm> -DLIB=<static library> -P ${CMAKE_CURRENT_LIST_FILE}")
endif()
if(NOT EXISTS "${LIB}")
  message(FATAL_ERROR "no_malloc: library not found: ${LIB}")
endif()

# The allocators of C (and POSIX / glibc extensions that allocate).
set(forbidden
  malloc calloc realloc free aligned_alloc posix_memalign
  memalign valloc pvalloc reallocarray strdup strndup)

# -A: prefix each line with "archive:object:", -u: undefined symbols only.
execute_process(
  COMMAND "${NM}" -A -u "${LIB}"
  OUTPUT_VARIABLE out
  ERROR_VARIABLE err
  RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "no_malloc: '${NM} -A -u ${LIB}' failed (${rc}): ${err}")
endif()

# Sanity check that nm can read the archive at all (a wrong-architecture nm
# prints "file format not recognized" and would otherwise pass vacuously).
execute_process(
  COMMAND "${NM}" -A --defined-only "${LIB}"
  OUTPUT_VARIABLE defined
  ERROR_VARIABLE err
  RESULT_VARIABLE rc)
if(NOT rc EQUAL 0 OR NOT defined MATCHES " [Tt] ")
  message(FATAL_ERROR "no_malloc: '${NM}' found no code in ${LIB}: ${err}")
endif()

string(REPLACE "\n" ";" lines "${out}")
list(JOIN forbidden "|" alternatives)
set(offenders "")
foreach(line IN LISTS lines)
  # e.g. "libtrn.a:grid.c.o:                 U malloc"
  if(line MATCHES "^(.*):[ \t]+U[ \t]+(${alternatives})(@.*)?$")
    list(APPEND offenders "  ${CMAKE_MATCH_1}: ${CMAKE_MATCH_2}")
  endif()
endforeach()

if(offenders)
  list(JOIN offenders "\n" report)
  message(FATAL_ERROR "no_malloc: ${LIB} references heap allocation:\n${report}")
endif()
message(STATUS "no_malloc: ${LIB} references no allocator")
