/* SPDX-License-Identifier: Apache-2.0 */
/*
 * ktest.h - the few checks the kernel tests need (cmocka has no static
 * library on Debian, and the VM runs static programs only).
 *
 * Output, one line each, read by run-vm.sh with grep -a:
 *   KT-CASE <name>                 a case starts
 *   KT-FAIL <file>:<line>: <what>  a check failed (the case goes on)
 *   KT-RESULT <prog> cases=N checks=C failed=F
 * The program's exit status is 0 only if no check failed.
 */
#ifndef TRN_KTEST_H
#define TRN_KTEST_H

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "trn/status.h"

static int kt_checks;
static int kt_failed;
static int kt_cases;

#define KT_CHECK(cond) \
    do { \
        ++kt_checks; \
        if (!(cond)) { \
            ++kt_failed; \
            (void)printf("KT-FAIL %s:%d: %s\n", __FILE__, __LINE__, #cond); \
            (void)fflush(stdout); \
        } \
    } while (0)

/* Status check that prints both names when it fails. */
#define KT_ST(got, want) \
    do { \
        trn_status_t kt_g_ = (got); \
        trn_status_t kt_w_ = (want); \
        ++kt_checks; \
        if (kt_g_ != kt_w_) { \
            ++kt_failed; \
            (void)printf("KT-FAIL %s:%d: %s gave %d (%s), want %d (%s)\n", __FILE__, __LINE__, \
                         #got, (int)kt_g_, trn_strerror(kt_g_), (int)kt_w_, trn_strerror(kt_w_)); \
            (void)fflush(stdout); \
        } \
    } while (0)

#define KT_RUN(fn) \
    do { \
        ++kt_cases; \
        (void)printf("KT-CASE %s\n", #fn); \
        (void)fflush(stdout); \
        fn(); \
    } while (0)

static inline int kt_finish(const char *prog)
{
    (void)printf("KT-RESULT %s cases=%d checks=%d failed=%d\n", prog, kt_cases, kt_checks,
                 kt_failed);
    (void)fflush(stdout);
    return kt_failed == 0 && kt_checks > 0 ? 0 : 1;
}

/* Monotonic milliseconds. */
static inline long long kt_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (long long)ts.tv_sec * 1000LL + ts.tv_nsec / 1000000L;
}

static inline void kt_sleep_ms(long ms)
{
    struct timespec ts;
    ts.tv_sec = ms / 1000;
    ts.tv_nsec = (ms % 1000) * 1000000L;
    while (nanosleep(&ts, &ts) != 0) {
    }
}

static inline const char *kt_env(const char *name, const char *dflt)
{
    const char *v = getenv(name);
    return v != NULL && v[0] != '\0' ? v : dflt;
}

#endif
