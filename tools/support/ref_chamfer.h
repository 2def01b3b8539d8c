/* SPDX-License-Identifier: Apache-2.0 */
/* ref_chamfer.h - slow, obvious oracles for the chamfer transform (tests and
 * benchmarks only; they allocate with malloc and are not part of the core). */
#ifndef TRN_SUPPORT_REF_CHAMFER_H
#define TRN_SUPPORT_REF_CHAMFER_H
#include <stdint.h>

/**
 * Exact 26-neighbour 3-4-5 chamfer distance of every voxel to the nearest
 * occupied one (occ nonzero), by Dijkstra's algorithm with a binary heap over
 * the voxel graph of the box (face step 3, edge step 4, corner step 5),
 * computed uncapped and then stored as min(d, cap). Voxel (x, y, z) is
 * index (z * ny + y) * nx + x. With no occupied voxel every entry is cap.
 * occ and dist may be the same memory. Aborts if malloc fails.
 */
void ref_chamfer3d_dijkstra(const uint8_t *occ, uint8_t *dist, int nx, int ny, int nz,
                            unsigned cap);

/** Largest value ref_euclid_nearest returns: "no occupied voxel". */
#define REF_EUCLID_NONE 1.0e30

/**
 * Brute-force Euclidean distance, in voxel sides, from voxel (x, y, z) to the
 * nearest occupied voxel; REF_EUCLID_NONE if none is occupied.
 */
double ref_euclid_nearest(const uint8_t *occ, int nx, int ny, int nz, int x, int y, int z);

#endif
