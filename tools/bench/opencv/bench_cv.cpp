/* SPDX-License-Identifier: Apache-2.0 */
// bench_cv.cpp - OpenCV reference for trn_bench: cv::distanceTransform on
// every z-slice of an occupancy volume (see bench_cv.h). Host-only benchmark
// code; it allocates freely, but only in bench_cv_dt_create.
#include "bench_cv.h"

#include <exception>
#include <new>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/version.hpp>
#include <opencv2/imgproc.hpp>

struct bench_cv_dt {
    std::vector<cv::Mat> src;  // CV_8UC1, 255 = free, 0 = occupied
    std::vector<cv::Mat> dst;  // CV_32FC1, preallocated
};

extern "C" const char *bench_cv_version(void) { return CV_VERSION; }

extern "C" int bench_cv_single_thread(void)
{
    try {
        cv::setNumThreads(1);
        return cv::getNumThreads();
    } catch (const std::exception &) {
        return -1;
    }
}

extern "C" bench_cv_dt_t *bench_cv_dt_create(const uint8_t *occ, int nx, int ny, int nz)
{
    if (occ == nullptr || nx < 1 || ny < 1 || nz < 1) {
        return nullptr;
    }
    bench_cv_dt_t *c = nullptr;
    try {
        c = new bench_cv_dt_t;
        const size_t plane = static_cast<size_t>(nx) * static_cast<size_t>(ny);
        c->src.reserve(static_cast<size_t>(nz));
        c->dst.reserve(static_cast<size_t>(nz));
        for (int z = 0; z < nz; ++z) {
            cv::Mat s(ny, nx, CV_8UC1);
            const uint8_t *o = occ + static_cast<size_t>(z) * plane;
            for (int y = 0; y < ny; ++y) {
                uint8_t *row = s.ptr<uint8_t>(y);
                const uint8_t *orow = o + static_cast<size_t>(y) * static_cast<size_t>(nx);
                for (int x = 0; x < nx; ++x) {
                    row[x] = orow[x] != 0u ? 0u : 255u;
                }
            }
            c->src.push_back(s);
            c->dst.push_back(cv::Mat::zeros(ny, nx, CV_32FC1));
        }
        return c;
    } catch (const std::exception &) {
        delete c;
        return nullptr;
    }
}

extern "C" int bench_cv_dt_run(bench_cv_dt_t *c, int mask)
{
    if (c == nullptr || (mask != 3 && mask != 5 && mask != 0)) {
        return -1;
    }
    const int ms = mask == 0 ? static_cast<int>(cv::DIST_MASK_PRECISE) : mask;
    try {
        for (size_t z = 0; z < c->src.size(); ++z) {
            cv::distanceTransform(c->src[z], c->dst[z], cv::DIST_L2, ms, CV_32F);
        }
    } catch (const std::exception &) {
        return -1;
    }
    return 0;
}

extern "C" double bench_cv_dt_checksum(const bench_cv_dt_t *c)
{
    double s = 0.0;
    if (c == nullptr) {
        return 0.0;
    }
    for (const cv::Mat &d : c->dst) {
        s += cv::sum(d)[0];
    }
    return s;
}

extern "C" void bench_cv_dt_destroy(bench_cv_dt_t *c) { delete c; }

// ---------------------------------------------------------------------------
// sepFilter2D: the fixed-sigma filter a user could reach for instead of the
// position-variant probability map.

struct bench_cv_sep {
    std::vector<cv::Mat> src;  // CV_32FC1, 1 = occupied
    std::vector<cv::Mat> dst;  // CV_32FC1
    cv::Mat k;                 // ksize x 1, CV_32F
};

extern "C" bench_cv_sep_t *bench_cv_sep_create(const uint8_t *occ, int occ_zero, int nx, int ny,
                                               int nz, const float *kernel, int ksize)
{
    if (occ == nullptr || kernel == nullptr || nx < 1 || ny < 1 || nz < 1 || ksize < 1) {
        return nullptr;
    }
    bench_cv_sep_t *c = nullptr;
    try {
        c = new bench_cv_sep_t;
        const size_t plane = static_cast<size_t>(nx) * static_cast<size_t>(ny);
        c->k = cv::Mat(ksize, 1, CV_32F);
        for (int i = 0; i < ksize; ++i) {
            c->k.at<float>(i, 0) = kernel[i];
        }
        for (int z = 0; z < nz; ++z) {
            cv::Mat s(ny, nx, CV_32FC1);
            const uint8_t *o = occ + static_cast<size_t>(z) * plane;
            for (int y = 0; y < ny; ++y) {
                float *row = s.ptr<float>(y);
                const uint8_t *orow = o + static_cast<size_t>(y) * static_cast<size_t>(nx);
                for (int x = 0; x < nx; ++x) {
                    const bool on = occ_zero ? orow[x] == 0u : orow[x] != 0u;
                    row[x] = on ? 1.0f : 0.0f;
                }
            }
            c->src.push_back(s);
            c->dst.push_back(cv::Mat::zeros(ny, nx, CV_32FC1));
        }
        return c;
    } catch (const std::exception &) {
        delete c;
        return nullptr;
    }
}

extern "C" int bench_cv_sep_run(bench_cv_sep_t *c)
{
    if (c == nullptr) {
        return -1;
    }
    try {
        for (size_t z = 0; z < c->src.size(); ++z) {
            cv::sepFilter2D(c->src[z], c->dst[z], CV_32F, c->k, c->k, cv::Point(-1, -1), 0.0,
                            cv::BORDER_CONSTANT);
        }
    } catch (const std::exception &) {
        return -1;
    }
    return 0;
}

extern "C" double bench_cv_sep_checksum(const bench_cv_sep_t *c)
{
    double s = 0.0;
    if (c == nullptr) {
        return 0.0;
    }
    for (const cv::Mat &d : c->dst) {
        s += cv::sum(d)[0];
    }
    return s;
}

extern "C" void bench_cv_sep_destroy(bench_cv_sep_t *c) { delete c; }
