/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file chamfer.h
 * @brief 3-D chamfer distance transform (method.md 2.4): the distance from
 * every voxel to the nearest occupied voxel of the global occupancy grid,
 * the D(.) of the paper's eq. 1, computed once per global map.
 *
 * Weights are Borgefors' 3-4-5 (face, edge and corner steps of the 3x3x3
 * neighbourhood), so one voxel side is 3 chamfer units. Two raster passes
 * (forward: the 12 neighbours in earlier rows, then both in-row neighbours
 * on rows holding an occupied voxel; backward: the 12 neighbours in later
 * rows) give the exact shortest path length over those 26 steps. Distances
 * are capped: a voxel farther than `cap` from every occupied voxel holds `cap`.
 * Voxels are treated as cubes (choose the height bin equal to the cell size).
 */
#ifndef TRN_CHAMFER_H
#define TRN_CHAMFER_H

#include "trn/grid.h"

#ifdef __cplusplus
extern "C" {
#endif

#define TRN_CHAMFER_FACE 3u   /**< weight of a face step (one voxel side) */
#define TRN_CHAMFER_EDGE 4u   /**< weight of an edge (2-D diagonal) step */
#define TRN_CHAMFER_CORNER 5u /**< weight of a corner (3-D diagonal) step */

/**
 * @brief Chamfer distance transform, in place allowed.
 *
 * Occupied voxels get 0, every other voxel min(D, cap) where D is the
 * length of the shortest 3-4-5 path (within the volume) to an occupied
 * voxel; D / 3 is within -5.8 % .. +10.6 % of the Euclidean distance in
 * voxel sides. Time O(nx ny nz); no allocation, a few hundred bytes of stack.
 *
 * @param[in]  occ  occupancy: nonzero = occupied, 0 = free.
 * @param[out] dist distances in chamfer units, min(true chamfer distance, cap);
 *                  same dimensions as occ; may be the same memory as occ,
 *                  otherwise must not overlap it.
 * @param[in]  cap  largest stored distance, 3..TRN_CHAMFER_CAP_MAX.
 * @retval TRN_OK
 * @retval TRN_E_NULL   occ, dist or their data NULL
 * @retval TRN_E_SIZE   bad dimensions or occ and dist differ in size
 * @retval TRN_E_ARG    cap out of range, or occ and dist partly overlap
 * @retval TRN_E_NODATA no voxel is occupied (dist is then all cap)
 * On TRN_E_NULL, TRN_E_SIZE and TRN_E_ARG dist is left untouched.
 */
trn_status_t trn_chamfer3d(const trn_vol_u8_t *occ, trn_vol_u8_t *dist, uint8_t cap);

#ifdef __cplusplus
}
#endif
#endif /* TRN_CHAMFER_H */
