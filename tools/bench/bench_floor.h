/* SPDX-License-Identifier: Apache-2.0 */
/* bench_floor.h - the timing floor of a two-pass 3-4-5 chamfer transform,
 * for trn_bench's "chamfer:" rows (see bench_floor.c). Bench code, not core. */
#ifndef TRN_BENCH_FLOOR_H
#define TRN_BENCH_FLOOR_H
#include <stddef.h>
#include <stdint.h>

/* Scratch bytes bench_relax_floor needs for rows of nx voxels. */
size_t bench_relax_floor_scratch(size_t nx);

/*
 * The out-of-row relaxation of both raster passes over the nx*ny*nz volume
 * v (forward from occ, then backward in place), with no in-row work at all
 * and the volume's faces skipped: the distances it leaves are NOT a
 * transform. It is timed only: the part of trn_chamfer3d's work that every
 * voxel needs, in the same form, so trn_chamfer3d cannot be faster than it.
 * scratch: bench_relax_floor_scratch(nx)
 * bytes. Requires nx >= 18, ny >= 3, nz >= 2, cap <= 250.
 */
void bench_relax_floor(const uint8_t *occ, uint8_t *v, size_t nx, size_t ny, size_t nz, uint8_t cap,
                       uint8_t *scratch);
#endif
