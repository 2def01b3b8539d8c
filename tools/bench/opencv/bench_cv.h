/* SPDX-License-Identifier: Apache-2.0 */
/* bench_cv.h - the C interface of trn_bench's OpenCV reference (bench_cv.cpp).
 *
 * Built only when CMake finds OpenCV (core, imgproc); the target then defines
 * TRN_HAVE_OPENCV=1 and the C main calls these functions. No C++ exception
 * crosses this interface: every failure is a return value.
 */
#ifndef TRN_BENCH_CV_H
#define TRN_BENCH_CV_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Opaque: the nz 2-D input slices and their float outputs, allocated once. */
typedef struct bench_cv_dt bench_cv_dt_t;

/** OpenCV's version string (CV_VERSION of the headers built against). */
const char *bench_cv_version(void);

/**
 * Make OpenCV run sequentially: cv::setNumThreads(1). (With Debian's TBB
 * backend, setNumThreads(0) also runs parallel_for_ bodies sequentially, but
 * getNumThreads() then still reports the TBB default; 1 reports 1.)
 * @return cv::getNumThreads() afterwards (1 when sequential), -1 on error.
 */
int bench_cv_single_thread(void);

/**
 * Prepare the slices of an occupancy volume: slice z is an ny x nx CV_8UC1
 * image, 255 where voxel (x, y, z) is free (occ == 0), 0 where it is
 * occupied (distanceTransform measures the distance to the nearest zero);
 * its output is an ny x nx CV_32FC1 image, allocated here once.
 * Voxel (x, y, z) is occ[(z * ny + y) * nx + x], as in trn_vol_u8_t.
 * @return NULL on bad sizes or out of memory.
 */
bench_cv_dt_t *bench_cv_dt_create(const uint8_t *occ, int nx, int ny, int nz);

/**
 * cv::distanceTransform(slice, out, cv::DIST_L2, mask, CV_32F) for every
 * slice z = 0..nz-1, into the preallocated outputs.
 * @param mask 3, 5, or 0 for cv::DIST_MASK_PRECISE (exact Euclidean).
 * @return 0 on success, -1 on a bad mask or an OpenCV exception.
 */
int bench_cv_dt_run(bench_cv_dt_t *c, int mask);

/** Sum of every output pixel of the last run (keeps the work observable). */
double bench_cv_dt_checksum(const bench_cv_dt_t *c);

/** Free everything bench_cv_dt_create allocated; NULL is a no-op. */
void bench_cv_dt_destroy(bench_cv_dt_t *c);

/** Opaque: nz float slices (0/1 occupancy), their outputs and one kernel. */
typedef struct bench_cv_sep bench_cv_sep_t;

/**
 * Prepare cv::sepFilter2D on every z slice of an occupancy volume: slice z is
 * an ny x nx CV_32FC1 image, 1 where voxel (x, y, z) is occupied (occ_zero
 * = 0: occ != 0; occ_zero = 1: occ == 0, for a chamfer distance volume), 0
 * elsewhere; outputs CV_32FC1 allocated here once; the same ksize-tap kernel
 * in x and y.
 * @return NULL on bad sizes or out of memory.
 */
bench_cv_sep_t *bench_cv_sep_create(const uint8_t *occ, int occ_zero, int nx, int ny, int nz,
                                    const float *kernel, int ksize);

/** cv::sepFilter2D(slice, out, CV_32F, k, k, anchor centre, 0, BORDER_CONSTANT)
 * for every slice. @return 0, or -1 on an OpenCV exception. */
int bench_cv_sep_run(bench_cv_sep_t *c);

/** Sum of every output pixel of the last run. */
double bench_cv_sep_checksum(const bench_cv_sep_t *c);

/** Free; NULL is a no-op. */
void bench_cv_sep_destroy(bench_cv_sep_t *c);

#ifdef __cplusplus
}
#endif
#endif /* TRN_BENCH_CV_H */
