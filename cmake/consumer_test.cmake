# SPDX-License-Identifier: Apache-2.0
# consumer_test.cmake - the `find_package_consumer` CTest test.
#
# Installs the already-built trn into a scratch prefix inside the build tree,
# then configures, builds and runs tests/consumer/, a separate CMake project
# that uses only `find_package(trn CONFIG REQUIRED)` and `trn::trn`. This checks
# the installed headers, libtrn.a, trnTargets.cmake and trnConfig*.cmake
# together, the way an integrator would use them.
#
#   cmake -DTRN_BINARY_DIR=... -DCONSUMER_SOURCE_DIR=... -DWORK_DIR=...
#         -DGENERATOR=... -DMAKE_PROGRAM=... -DC_COMPILER=... -DBUILD_TYPE=...
#         -DC_FLAGS=... -DLINKER_FLAGS=... -P consumer_test.cmake

foreach(var TRN_BINARY_DIR CONSUMER_SOURCE_DIR WORK_DIR GENERATOR C_COMPILER)
  if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
    message(FATAL_ERROR "consumer_test.cmake: ${var} not set")
  endif()
endforeach()

set(prefix "${WORK_DIR}/prefix")
set(build "${WORK_DIR}/build")
# Start from nothing each time so a stale install or cache cannot hide a bug.
file(REMOVE_RECURSE "${WORK_DIR}")

function(run)
  message(STATUS "consumer: ${ARGV}")
  execute_process(COMMAND ${ARGV} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "consumer: command failed (${rc}): ${ARGV}")
  endif()
endfunction()

# 1. install
set(install_args --install "${TRN_BINARY_DIR}" --prefix "${prefix}")
if(BUILD_TYPE)
  list(APPEND install_args --config "${BUILD_TYPE}")
endif()
run("${CMAKE_COMMAND}" ${install_args})

# 2. configure the consumer against the installed package only. The same
# compiler and flags as the parent build are passed on, because the parent's
# flags (e.g. -fsanitize=address) are baked into libtrn.a.
set(configure_args
  -S "${CONSUMER_SOURCE_DIR}" -B "${build}"
  -G "${GENERATOR}"
  "-DCMAKE_PREFIX_PATH=${prefix}"
  "-DCMAKE_C_COMPILER=${C_COMPILER}"
  "-DCMAKE_BUILD_TYPE=${BUILD_TYPE}"
  "-DCMAKE_C_FLAGS=${C_FLAGS}"
  "-DCMAKE_EXE_LINKER_FLAGS=${LINKER_FLAGS}")
if(MAKE_PROGRAM)
  list(APPEND configure_args "-DCMAKE_MAKE_PROGRAM=${MAKE_PROGRAM}")
endif()
run("${CMAKE_COMMAND}" ${configure_args})

# 3. build, 4. run
run("${CMAKE_COMMAND}" --build "${build}")
run("${build}/trn_consumer")
message(STATUS "consumer: find_package(trn) consumer built and ran")
