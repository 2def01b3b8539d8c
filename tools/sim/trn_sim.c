/* SPDX-License-Identifier: Apache-2.0 */
/* trn_sim.c - the mast and stereo-head simulator as a program (docs/modules/sim.md).
 *
 *   trn_sim [--if vcan0] [--seed N] [--terrain-seed N] [--size CELLS] [--cell M]
 *           [--pose X,Y,HEADING] [--run-ms MS] [--trigger VALUE_FILE]
 *           [--fault none|drop|corrupt|silent|stuck-pan|bus-off] [--fault-arg N]
 *
 * Terrain: tools/support/synth (rocks on a rolling background), size x size
 * cells of --cell metres from (0, 0); the rover stands at --pose.
 * Runs until --run-ms or SIGINT/SIGTERM, then prints its counters. */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim_node.h"
#include "synth.h"

static volatile sig_atomic_t g_stop;

static void on_signal(int sig)
{
    (void)sig;
    g_stop = 1;
}

static int usage(void)
{
    fprintf(
        stderr,
        "usage: trn_sim [--if IF] [--seed N] [--terrain-seed N] [--size CELLS] [--cell M]\n"
        "               [--pose X,Y,HEADING] [--run-ms MS] [--trigger VALUE_FILE]\n"
        "               [--fault none|drop|corrupt|silent|stuck-pan|bus-off] [--fault-arg N]\n");
    return 2;
}

/* "X,Y,HEADING": three finite floats and nothing else; 1 ok. */
static int parse_pose(const char *s, float v[3])
{
    int k;
    for (k = 0; k < 3; ++k) {
        char *end = NULL;
        errno = 0;
        v[k] = strtof(s, &end);
        if (end == s || errno == ERANGE || *end != (k < 2 ? ',' : '\0')) {
            return 0;
        }
        s = end + 1;
    }
    return 1;
}

int main(int argc, char **argv)
{
    static synth_rock_t rocks[4000];
    sim_cfg_t cfg;
    sim_stats_t stats;
    synth_terrain_t terr;
    unsigned long tseed = 12;
    long size = 256;
    double cell = 0.05;
    float *dem;
    size_t nrocks;
    int i;
    trn_status_t st;
    sim_cfg_default(&cfg);
    cfg.pose.x_m = 6.0f;
    cfg.pose.y_m = 6.0f;
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (v == NULL) {
            return usage();
        }
        if (strcmp(a, "--if") == 0) {
            cfg.ifname = v;
        } else if (strcmp(a, "--seed") == 0) {
            cfg.seed = strtoull(v, NULL, 0);
        } else if (strcmp(a, "--terrain-seed") == 0) {
            tseed = strtoul(v, NULL, 0);
        } else if (strcmp(a, "--size") == 0) {
            size = strtol(v, NULL, 0);
        } else if (strcmp(a, "--cell") == 0) {
            cell = strtod(v, NULL);
        } else if (strcmp(a, "--pose") == 0) {
            float pose[3];
            if (!parse_pose(v, pose)) {
                return usage();
            }
            cfg.pose.x_m = pose[0];
            cfg.pose.y_m = pose[1];
            cfg.pose.heading_rad = pose[2];
        } else if (strcmp(a, "--run-ms") == 0) {
            cfg.run_ms = (uint32_t)strtoul(v, NULL, 0);
        } else if (strcmp(a, "--trigger") == 0) {
            cfg.trigger_path = v;
        } else if (strcmp(a, "--fault-arg") == 0) {
            cfg.fault_arg = (uint32_t)strtoul(v, NULL, 0);
        } else if (strcmp(a, "--fault") == 0) {
            int f, found = 0;
            for (f = 0; f < SIM_FAULT_COUNT; ++f) {
                if (strcmp(v, sim_fault_name((sim_fault_t)f)) == 0) {
                    cfg.fault = (sim_fault_t)f;
                    found = 1;
                }
            }
            if (!found) {
                return usage();
            }
        } else {
            return usage();
        }
        ++i;
    }
    if (size < 16 || size > 4096 || !(cell > 0.0 && cell <= 10.0)) {
        return usage();
    }
    nrocks = (size_t)((double)size * (double)size * cell * cell * 0.15 / (3.14159 * 0.15 * 0.15));
    if (nrocks > 4000) {
        nrocks = 4000;
    }
    dem = (float *)malloc(sizeof(float) * (size_t)size * (size_t)size);
    if (dem == NULL) {
        return 1;
    }
    synth_make(&terr, rocks, nrocks, (double)size * cell, 0.05, 0.3, 0.5, 0.2, tseed);
    synth_render(&terr, dem, (int)size, (int)size, 0.0, 0.0, cell);
    cfg.dem.heights = dem;
    cfg.dem.width = (int32_t)size;
    cfg.dem.height = (int32_t)size;
    cfg.dem.cell_m = (float)cell;
    cfg.pose.z_m = (float)synth_height(&terr, cfg.pose.x_m, cfg.pose.y_m);
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    st = sim_run(&cfg, &g_stop, &stats);
    printf(
        "trn_sim: %s; cmds=%u capture_cmds=%u captures=%u data_frames=%u dropped=%u corrupted=%u "
        "error_frames=%u triggers=%u last: points=%u bytes=%u segments=%u\n",
        trn_strerror(st), stats.cmds, stats.capture_cmds, stats.captures_sent, stats.data_frames,
        stats.dropped_frames, stats.corrupted, stats.error_frames, stats.triggers,
        stats.last_points, stats.last_bytes, stats.last_segments);
    free(dem);
    return st == TRN_OK ? 0 : 1;
}
