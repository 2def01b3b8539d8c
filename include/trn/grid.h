/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file grid.h
 * @brief Views over caller-owned memory: 2-D float grids (DEMs, probability
 * maps) and 3-D uint8 volumes (occupancy, chamfer distances).
 *
 * A view never owns its memory and never allocates. Coordinates: x is the
 * column (0..width-1), y the row (0..height-1), z the height bin. A 2-D grid
 * may be a sub-view of a larger one (stride > width). A volume is dense:
 * voxel (x, y, z) is data[((size_t)z * ny + y) * nx + x].
 */
#ifndef TRN_GRID_H
#define TRN_GRID_H

#include <stddef.h>
#include <stdint.h>
#include "trn/status.h"
#include "trn/trn_config.h"

#ifdef __cplusplus
extern "C" {
#endif

/** 2-D grid of float, row-major. Missing data is NaN. */
typedef struct {
    float *data;    /**< first cell; at least (height-1)*stride + width elements */
    int32_t width;  /**< cells per row, 1..TRN_MAX_DIM */
    int32_t height; /**< rows, 1..TRN_MAX_DIM */
    int32_t stride; /**< elements between rows, >= width */
} trn_grid_f32_t;

/** Dense 3-D volume of uint8_t. */
typedef struct {
    uint8_t *data; /**< nx*ny*nz bytes */
    int32_t nx;    /**< 1..TRN_MAX_DIM */
    int32_t ny;    /**< 1..TRN_MAX_DIM */
    int32_t nz;    /**< 1..TRN_MAX_ZBINS */
} trn_vol_u8_t;

/**
 * @brief Make a grid view over caller memory (stride = width).
 * @param[out] g        the view.
 * @param[in]  data     caller memory of at least width*height floats.
 * @param[in]  capacity number of floats available at data.
 * @retval TRN_OK, TRN_E_NULL (g or data NULL), TRN_E_SIZE (dimension 0 or
 *         > TRN_MAX_DIM), TRN_E_WORKSPACE (capacity < width*height).
 */
trn_status_t trn_grid_f32_init(trn_grid_f32_t *g, float *data, size_t capacity, int32_t width,
                               int32_t height);

/**
 * @brief Check a grid view a caller filled in by hand.
 * @retval TRN_OK, TRN_E_NULL (g or g->data NULL), TRN_E_SIZE (dimensions
 *         out of range or stride < width).
 */
trn_status_t trn_grid_f32_check(const trn_grid_f32_t *g);

/**
 * @brief A sub-view of g (no copy): cells [x0, x0+width) x [y0, y0+height).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_SIZE (bad g or zero size), TRN_E_RANGE
 *         (the rectangle is not inside g).
 */
trn_status_t trn_grid_f32_sub(const trn_grid_f32_t *g, int32_t x0, int32_t y0, int32_t width,
                              int32_t height, trn_grid_f32_t *sub);

/**
 * @brief Make a volume view over caller memory.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_SIZE (nx, ny out of 1..TRN_MAX_DIM or nz
 *         out of 1..TRN_MAX_ZBINS), TRN_E_WORKSPACE (capacity < nx*ny*nz).
 */
trn_status_t trn_vol_u8_init(trn_vol_u8_t *v, uint8_t *data, size_t capacity, int32_t nx,
                             int32_t ny, int32_t nz);

/**
 * @brief Check a volume view a caller filled in by hand.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_SIZE.
 */
trn_status_t trn_vol_u8_check(const trn_vol_u8_t *v);

/** Cell (x, y) of a grid; no bounds check (callers check first). */
#define TRN_GRID_AT(g, x, y) ((g)->data[(size_t)(y) * (size_t)(g)->stride + (size_t)(x)])
/** Linear index of voxel (x, y, z); no bounds check. */
#define TRN_VOL_IDX(v, x, y, z) \
    ((((size_t)(z) * (size_t)(v)->ny) + (size_t)(y)) * (size_t)(v)->nx + (size_t)(x))

/**
 * Alignment, in bytes, of every workspace and map buffer a caller passes to
 * the core, and of every slice the core carves from one (a doubleword load
 * on a Cortex-R faults when misaligned; 16 also suits vector loads). A
 * function given a misaligned buffer returns TRN_E_WORKSPACE.
 */
#define TRN_WS_ALIGN 16u

/**
 * @brief Round a byte count up to TRN_WS_ALIGN, so sizing functions and
 * carvers agree.
 */
#define TRN_ALIGN_UP(n) (((size_t)(n) + ((size_t)TRN_WS_ALIGN - 1u)) & ~((size_t)TRN_WS_ALIGN - 1u))

/* The alignment specifier for TRN_WORKSPACE_DECLARE (C99 has none). */
#if defined(TRN_WS_ALIGNAS)
/* given by the integrator */
#elif defined(__GNUC__) || defined(__clang__)
#define TRN_WS_ALIGNAS __attribute__((aligned(16)))
#elif defined(__STDC_VERSION__) && (__STDC_VERSION__ >= 201112L)
#define TRN_WS_ALIGNAS _Alignas(16)
#elif defined(_MSC_VER)
#define TRN_WS_ALIGNAS __declspec(align(16))
#else
/* Unknown compiler: define TRN_WS_ALIGNAS to its 16-byte alignment specifier.
 * Without one a declared buffer is only byte-aligned, and every entry given
 * it when misaligned returns TRN_E_WORKSPACE (never a fault). */
#define TRN_WS_ALIGNAS
#endif

/**
 * @brief Declare a static, TRN_WS_ALIGN-aligned byte buffer for a workspace
 * or map: `TRN_WORKSPACE_DECLARE(map_mem, MAP_BYTES);` (bytes: a constant
 * expression, rounded up to TRN_WS_ALIGN). Use it at file or block scope.
 */
#define TRN_WORKSPACE_DECLARE(name, bytes) static TRN_WS_ALIGNAS uint8_t name[TRN_ALIGN_UP(bytes)]

#ifdef __cplusplus
}
#endif
#endif /* TRN_GRID_H */
