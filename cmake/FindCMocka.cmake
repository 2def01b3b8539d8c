# SPDX-License-Identifier: Apache-2.0
# FindCMocka.cmake - locate the cmocka unit-test library (Debian: libcmocka-dev).
#
# Plain find_path/find_library rather than pkg-config or cmocka's own CMake
# config, so the same code works natively and when cross-compiling against
# Debian multiarch (libcmocka-dev:arm64 in /usr/lib/aarch64-linux-gnu; the
# toolchain file sets CMAKE_LIBRARY_ARCHITECTURE and the find root paths).
#
# Result: CMocka_FOUND, CMOCKA_INCLUDE_DIR, CMOCKA_LIBRARY and the imported
# target CMocka::cmocka.

find_path(CMOCKA_INCLUDE_DIR NAMES cmocka.h)
find_library(CMOCKA_LIBRARY NAMES cmocka)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(CMocka
  REQUIRED_VARS CMOCKA_LIBRARY CMOCKA_INCLUDE_DIR)
mark_as_advanced(CMOCKA_INCLUDE_DIR CMOCKA_LIBRARY)

if(CMocka_FOUND AND NOT TARGET CMocka::cmocka)
  add_library(CMocka::cmocka UNKNOWN IMPORTED)
  set_target_properties(CMocka::cmocka PROPERTIES
    IMPORTED_LOCATION "${CMOCKA_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${CMOCKA_INCLUDE_DIR}")
endif()
