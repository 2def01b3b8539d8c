# SPDX-License-Identifier: Apache-2.0
# TrnWarnings.cmake - the one warning set of the project (docs/architecture.md,
# "Numbers"), applied to the core, the tests and the tools.
#
#   trn_apply_warnings(<target> [NO_CONVERSION])
#
# NO_CONVERSION drops -Wconversion and -Wdouble-promotion, for code (tools,
# third-party-heavy benches) where they are more noise than help. The core never
# uses it. C-only flags are limited to C sources so a C++ file in the same target
# (the optional OpenCV bench) compiles cleanly.

option(TRN_WARNINGS_AS_ERRORS "Treat compiler warnings as errors (-Werror)" ON)

function(trn_apply_warnings target)
  cmake_parse_arguments(ARG "NO_CONVERSION" "" "" ${ARGN})

  set(common -Wall -Wextra -pedantic -Wvla -Wshadow -Wcast-align)
  if(NOT ARG_NO_CONVERSION)
    list(APPEND common -Wconversion -Wdouble-promotion)
  endif()
  if(TRN_WARNINGS_AS_ERRORS)
    list(APPEND common -Werror)
  endif()
  set(c_only -Wstrict-prototypes -Wmissing-prototypes)

  target_compile_options(${target} PRIVATE
    ${common}
    "$<$<COMPILE_LANGUAGE:C>:${c_only}>")

  # -std=c99 exactly: no GNU extensions.
  set_target_properties(${target} PROPERTIES
    C_STANDARD 99
    C_STANDARD_REQUIRED ON
    C_EXTENSIONS OFF)
endfunction()
