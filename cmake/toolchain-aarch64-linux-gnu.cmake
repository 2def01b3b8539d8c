# SPDX-License-Identifier: Apache-2.0
# Cross toolchain: 64-bit ARM Linux (Debian's gcc-aarch64-linux-gnu).
#
# Libraries come from Debian multiarch: `dpkg --add-architecture arm64` puts
# arm64 packages (libcmocka-dev:arm64, libc6:arm64) under
# /usr/lib/aarch64-linux-gnu, and headers in /usr/include are shared.
# The cross libc itself lives under /usr/aarch64-linux-gnu (libc6-dev-arm64-cross).
#
# Tests run on the build machine through qemu-user; `-L` tells qemu where the
# arm64 dynamic loader and libc live.

set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
# CMake derives CMAKE_NM, CMAKE_AR, ... from the compiler's prefix, so
# CMAKE_NM becomes aarch64-linux-gnu-nm (used by the no_malloc test).

# Search /usr/lib/aarch64-linux-gnu (multiarch) and the cross sysroot for
# libraries and headers, never the host's x86_64 directories; programs
# (pkg-config, nm, ...) come from the host.
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu /)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config, should anything use it: arm64 .pc files only.
set(ENV{PKG_CONFIG_LIBDIR} "/usr/lib/aarch64-linux-gnu/pkgconfig:/usr/share/pkgconfig")

# add_test() commands and try_run() go through this emulator.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64 -L /usr/aarch64-linux-gnu)
