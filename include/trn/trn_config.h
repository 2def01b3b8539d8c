/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file trn_config.h
 * @brief Compile-time maxima and build options of the trn core.
 *
 * Works like lwIP's opt.h: if the integrator defines TRN_USER_CONFIG_H (for
 * example `-DTRN_USER_CONFIG_H="rover_trn_opts.h"`), that header is read first
 * and may override any value below; every value here is a guarded default; an
 * inconsistent configuration stops the build with \#error.
 *
 * Every compile-time maximum of the core is here, and some size public
 * structs (trn_kernels_t, trn_lnp_table_t, trn_pyramid_t, trn_map_t), so the
 * library and every file that includes its headers must see the same
 * configuration. With CMake, set the cache variable TRN_USER_CONFIG_H: the
 * definition is then PUBLIC on the trn targets and reaches every consumer
 * (add_subdirectory); installed, the header is copied to
 * trn/trn_user_config.h and find_package and pkg-config consumers get
 * TRN_INSTALLED_USER_CONFIG, which includes it. Otherwise define it for the
 * whole build. TRN_ABI_CHECK() (trn/abi.h) tells at run time whether a file and
 * the library agree.
 */
#ifndef TRN_CONFIG_H
#define TRN_CONFIG_H

#ifdef TRN_USER_CONFIG_H
#include TRN_USER_CONFIG_H
#elif defined(TRN_INSTALLED_USER_CONFIG)
/* an installed trn built with TRN_USER_CONFIG_H: its copy of that header
 * (the installed CMake package and trn.pc define this macro) */
#include "trn/trn_user_config.h"
#endif

/** Largest grid side, in cells, any module accepts (x or y). */
#ifndef TRN_MAX_DIM
#define TRN_MAX_DIM 4096
#endif

/** Largest number of height bins of an occupancy volume. */
#ifndef TRN_MAX_ZBINS
#define TRN_MAX_ZBINS 128
#endif

/**
 * Largest chamfer distance stored, in chamfer units (one face step = 3).
 * Distances are stored in uint8_t and step weights go up to 5, so the cap
 * must leave room: cap + 5 <= 255.
 */
#ifndef TRN_CHAMFER_CAP_MAX
#define TRN_CHAMFER_CAP_MAX 250
#endif

/** Largest number of branch-and-bound pyramid levels (blocks of 2^L poses). */
#ifndef TRN_MAX_LEVELS
#define TRN_MAX_LEVELS 6
#endif

/** Largest kernel radius, taps each side; trn_kernels_t stores 10 x (2 R + 1) floats. */
#ifndef TRN_KERNEL_MAX_RADIUS
#define TRN_KERNEL_MAX_RADIUS 64
#endif

/** Largest number of headings (2 K + 1) trn_localize_points_heading searches. */
#ifndef TRN_MAX_HEADING_STEPS
#define TRN_MAX_HEADING_STEPS 1441
#endif

/**
 * Coarsest map cell the core accepts, metres: every check of a cell side
 * (and of the height bin, which equals the cell in the scaled map
 * configuration, and of the inlier spread s, one cell there too) allows
 * (0, TRN_CELL_MAX_M]. 10 km: a 900 m DEM averaged 4 x 4 has 3.6 km cells,
 * and the bound keeps the cell arithmetic (distances of up to
 * TRN_CHAMFER_CAP_MAX / 3 cells, ranges of TRN_MAX_DIM cells, their squares)
 * far from the float limits.
 */
#ifndef TRN_CELL_MAX_M
#define TRN_CELL_MAX_M 10000.0f
#endif

/** Fixed-point scale of log-likelihood tables: table units per nat. */
#ifndef TRN_LNP_SCALE
#define TRN_LNP_SCALE 65536
#endif

/**
 * Largest worst-case stack, in bytes, of any public function (its own frame
 * plus its deepest chain of callees, libm budgets included), as computed from
 * the build by tools/stack/trn_stack.py; the test command fails above it.
 * 2 KiB: a flight task on a Cortex-R5 RTOS typically gets 4-8 KiB of stack,
 * and the navigation call must leave at least half of the smallest of those
 * to the task's own frames, the RTOS context save (with the VFP registers)
 * and nested interrupts. The core keeps large data in caller workspaces, so
 * only fixed small tables (histograms, heaps of <= 1 KiB) live on the stack.
 * This is a check of the build, not a compile-time limit of the code.
 */
#ifndef TRN_STACK_LIMIT_BYTES
#define TRN_STACK_LIMIT_BYTES 2048
#endif

#if TRN_MAX_DIM < 8 || TRN_MAX_DIM > 16383
#error "TRN_MAX_DIM must be in [8, 16383] (local point offsets up to 2*TRN_MAX_DIM are int16_t)"
#endif
#if TRN_MAX_ZBINS < 1 || TRN_MAX_ZBINS > 255
#error "TRN_MAX_ZBINS must be in [1, 255]"
#endif
#if TRN_CHAMFER_CAP_MAX < 3 || TRN_CHAMFER_CAP_MAX > 250
#error "TRN_CHAMFER_CAP_MAX must be in [3, 250] (uint8_t storage, steps up to 5)"
#endif
#if TRN_MAX_LEVELS < 1 || TRN_MAX_LEVELS > 10
#error "TRN_MAX_LEVELS must be in [1, 10]"
#endif
#if TRN_KERNEL_MAX_RADIUS < 3 || TRN_KERNEL_MAX_RADIUS > 1024
#error "TRN_KERNEL_MAX_RADIUS must be in [3, 1024]"
#endif
#if TRN_MAX_HEADING_STEPS < 1 || TRN_MAX_HEADING_STEPS > 1000001
#error "TRN_MAX_HEADING_STEPS must be in [1, 1000001]"
#endif
#if TRN_LNP_SCALE < 1024 || TRN_LNP_SCALE > 1048576
#error "TRN_LNP_SCALE must be in [1024, 1048576]"
#endif

#if TRN_STACK_LIMIT_BYTES < 256
#error "TRN_STACK_LIMIT_BYTES must be at least 256"
#endif

/* TRN_CELL_MAX_M is a float, which #if cannot compare: a negative array
 * size stops the build instead when it is outside [1, 100000] m (up to
 * 100 km, the automatic configuration's 10-cell high-pass box stays within
 * the 10^6 m trn_terrain_cfg_check allows). */
typedef char trn_config_cell_max_m_must_be_in_1_to_100000
    [((long)(TRN_CELL_MAX_M) >= 1L && (long)(TRN_CELL_MAX_M) <= 100000L) ? 1 : -1];

#endif /* TRN_CONFIG_H */
