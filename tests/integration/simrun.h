/* SPDX-License-Identifier: Apache-2.0 */
/*
 * simrun.h - the simulator (tools/sim/sim_node.h) in a child process of a
 * kernel-test program: fork, run, stop with SIGTERM, read its counters back
 * through a pipe. Shared by kt_sim.c and kt_loop.c (header-only, static).
 */
#ifndef TRN_KT_SIMRUN_H
#define TRN_KT_SIMRUN_H

#include <signal.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "sim_node.h"

typedef struct {
    pid_t pid;
    int rd;            /* read end of the counters pipe */
    sim_stats_t stats; /* filled by simrun_stop */
} simrun_t;

static volatile sig_atomic_t simrun_stop_flag;

static void simrun_on_term(int sig)
{
    (void)sig;
    simrun_stop_flag = 1;
}

/* Start the simulator; returns 0 on success. It runs at most 60 s. */
static inline int simrun_start(simrun_t *r, const sim_cfg_t *cfg)
{
    int fds[2];
    memset(r, 0, sizeof *r);
    r->pid = -1;
    if (pipe(fds) != 0) {
        return -1;
    }
    r->pid = fork();
    if (r->pid < 0) {
        return -1;
    }
    if (r->pid == 0) {
        sim_cfg_t c = *cfg;
        sim_stats_t st;
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = simrun_on_term;
        sigaction(SIGTERM, &sa, NULL);
        close(fds[0]);
        if (c.run_ms == 0u) {
            c.run_ms = 60000u;
        }
        memset(&st, 0, sizeof st);
        {
            trn_status_t s = sim_run(&c, &simrun_stop_flag, &st);
            ssize_t w = write(fds[1], &st, sizeof st);
            _exit(s == TRN_OK && w == (ssize_t)sizeof st ? 0 : 1);
        }
    }
    close(fds[1]);
    r->rd = fds[0];
    /* let it open its socket and send its first heartbeats */
    kt_sleep_ms(50);
    return 0;
}

/* Stop it and collect its counters; returns its exit status (0 = ok). */
static inline int simrun_stop(simrun_t *r)
{
    int wst = 0;
    ssize_t got;
    if (r->pid <= 0) {
        return -1;
    }
    kill(r->pid, SIGTERM);
    got = read(r->rd, &r->stats, sizeof r->stats);
    close(r->rd);
    if (waitpid(r->pid, &wst, 0) != r->pid) {
        return -1;
    }
    r->pid = -1;
    if (got != (ssize_t)sizeof r->stats) {
        return -1;
    }
    return WIFEXITED(wst) ? WEXITSTATUS(wst) : -1;
}

#endif
