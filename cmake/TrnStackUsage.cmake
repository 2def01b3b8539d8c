# SPDX-License-Identifier: Apache-2.0
# TrnStackUsage.cmake - per-function stack sizes and call graphs from GCC, for
# tools/stack/trn_stack.py (docs/assurance.md, "Stack").
#
#   trn_enable_stack_usage(<target>)
#
# With TRN_STACK_USAGE on (the default with GCC), every object of <target> is
# compiled with -fstack-usage (<obj>.su: frame bytes per function) and
# -fcallgraph-info=su (<obj>.ci: the call graph with those sizes; GCC >= 10).
# The files sit next to the objects in the build tree; nothing else changes
# (same code, same flags otherwise). Applied to the core and the pure protocol
# library; other compilers (clang) silently skip it.

include(CheckCCompilerFlag)

if(CMAKE_C_COMPILER_ID STREQUAL "GNU")
  set(_trn_stack_default ON)
else()
  set(_trn_stack_default OFF)
endif()
option(TRN_STACK_USAGE "Write .su/.ci stack and call-graph files for the core (GCC)" ${_trn_stack_default})

if(TRN_STACK_USAGE)
  check_c_compiler_flag("-fstack-usage -fcallgraph-info=su" TRN_HAVE_CALLGRAPH_INFO)
  if(NOT TRN_HAVE_CALLGRAPH_INFO)
    message(STATUS "TRN_STACK_USAGE: ${CMAKE_C_COMPILER} lacks -fcallgraph-info=su; no stack files")
  endif()
endif()

function(trn_enable_stack_usage target)
  if(TRN_STACK_USAGE AND TRN_HAVE_CALLGRAPH_INFO)
    target_compile_options(${target} PRIVATE
      "$<$<COMPILE_LANGUAGE:C>:-fstack-usage;-fcallgraph-info=su>")
  endif()
endfunction()
