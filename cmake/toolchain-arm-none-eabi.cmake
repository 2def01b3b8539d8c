# SPDX-License-Identifier: Apache-2.0
# Cross toolchain: bare-metal ARM Cortex-R5F (TI Hercules-class flight
# processor) with Debian's gcc-arm-none-eabi + libnewlib-arm-none-eabi.
#
# Only the static library libtrn.a is built for this target (no tests, no
# tools): there is no OS to run them on, and linking an executable would need a
# board's linker script and startup code. try_compile() therefore builds static
# libraries instead of executables.
#
# Endianness: GCC's default (little-endian, as on RM4x/RM5x). TMS570 parts are
# big-endian BE32; an integrator targeting them adds -mbig-endian.

set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

# Cortex-R5 with VFPv3-D16 (double-precision FPU, 16 D registers), hard-float
# ABI, ARM (not Thumb) instruction set. One section per function and object so
# the final firmware link can drop what it does not use (--gc-sections).
set(TRN_ARM_CPU_FLAGS "-mcpu=cortex-r5 -mfpu=vfpv3-d16 -mfloat-abi=hard -marm")
set(CMAKE_C_FLAGS_INIT "${TRN_ARM_CPU_FLAGS} -ffunction-sections -fdata-sections")
set(CMAKE_CXX_FLAGS_INIT "${TRN_ARM_CPU_FLAGS} -ffunction-sections -fdata-sections")

# Nothing of the host may leak in: libraries and headers only from the
# toolchain's own sysroot, programs from the host.
set(CMAKE_FIND_ROOT_PATH /usr/lib/arm-none-eabi)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# binutils `size` for the per-build memory report (CMake finds nm/ar itself).
set(TRN_SIZE_TOOL arm-none-eabi-size)
