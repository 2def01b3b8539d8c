# SPDX-License-Identifier: Apache-2.0
# consumer_test.cmake - the `find_package_consumer` CTest test.
#
# Installs the already-built trn into a scratch prefix inside the build tree,
# then configures, builds and runs tests/consumer/, a separate CMake project
# that uses only `find_package(trn 0.1 CONFIG REQUIRED)` and the imported
# targets (trn::trn with trn::trn_proto, trn::trn_shared). This checks the
# installed headers, libtrn.a, libtrn.so, trnTargets.cmake and
# trnConfig*.cmake together, the way an integrator would use them. Then it
# compiles the same main.c with nothing but the compiler and
# `pkg-config --cflags --libs trn trn-proto` (PKG_CONFIG_PATH = the prefix's
# pkgconfig directory) and runs it, with LD_LIBRARY_PATH for libtrn.so.
#
#   cmake -DTRN_BINARY_DIR=... -DCONSUMER_SOURCE_DIR=... -DWORK_DIR=...
#         -DGENERATOR=... -DMAKE_PROGRAM=... -DC_COMPILER=... -DBUILD_TYPE=...
#         -DC_FLAGS=... -DLINKER_FLAGS=... -DTRN_VERSION=... -DPKG_CONFIG=...
#         -DLIBDIR=... -P consumer_test.cmake

foreach(var TRN_BINARY_DIR CONSUMER_SOURCE_DIR WORK_DIR GENERATOR C_COMPILER TRN_VERSION LIBDIR)
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

# 3. build, 4. run (static; shared when the package has libtrn.so)
run("${CMAKE_COMMAND}" --build "${build}")
run("${build}/trn_consumer")
if(EXISTS "${build}/trn_consumer_shared")
  run("${build}/trn_consumer_shared")
endif()
message(STATUS "consumer: find_package(trn) consumers built and ran")

# 5. pkg-config: the compiler and the .pc files only.
if(NOT PKG_CONFIG)
  message(FATAL_ERROR "consumer: pkg-config not found (bash tools/setup.sh core installs it)")
endif()
set(pcdir "${prefix}/${LIBDIR}/pkgconfig")
set(pcenv "${CMAKE_COMMAND}" -E env "PKG_CONFIG_PATH=${pcdir}")
execute_process(COMMAND ${pcenv} "${PKG_CONFIG}" --modversion trn
  OUTPUT_VARIABLE pc_version OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
if(NOT rc EQUAL 0 OR NOT pc_version STREQUAL TRN_VERSION)
  message(FATAL_ERROR "consumer: pkg-config --modversion trn: '${pc_version}' (${rc}), want ${TRN_VERSION}")
endif()
execute_process(COMMAND ${pcenv} "${PKG_CONFIG}" --cflags --libs trn trn-proto
  OUTPUT_VARIABLE pc_flags OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "consumer: pkg-config --cflags --libs trn trn-proto failed (${rc})")
endif()
message(STATUS "consumer: pkg-config trn ${pc_version}: ${pc_flags}")
separate_arguments(pc_flags UNIX_COMMAND "${pc_flags}")
separate_arguments(c_flags UNIX_COMMAND "${C_FLAGS}")
separate_arguments(ld_flags UNIX_COMMAND "${LINKER_FLAGS}")
set(pc_exe "${WORK_DIR}/trn_consumer_pkgconfig")
run("${C_COMPILER}" ${c_flags} -std=c99 -Wall -Wextra -pedantic -Werror
    "-DEXPECT_VERSION=\"${TRN_VERSION}\"" -DCONSUMER_PROTO=1
    "${CONSUMER_SOURCE_DIR}/main.c" -o "${pc_exe}" ${ld_flags} ${pc_flags})
run("${CMAKE_COMMAND}" -E env "LD_LIBRARY_PATH=${prefix}/${LIBDIR}" "${pc_exe}")
message(STATUS "consumer: pkg-config consumer built and ran")
