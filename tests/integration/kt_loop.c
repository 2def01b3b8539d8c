/* SPDX-License-Identifier: Apache-2.0 */
/*
 * kt_loop.c - the whole loop of issue 6 in the VM: the rover's software
 * (trn + port) against the mast and stereo-head simulator on vcan, with the
 * stereo trigger on a gpio-sim line.
 *
 * Per seeded run: a synthetic global DEM (tools/support/synth, 19.2 m at
 * 0.1 m) -> trn_map_build + eq. 8 probability map -> trn_select picks the
 * target from the rover's believed position (the truth plus a prior offset
 * of up to 0.8 m per axis; bearings within the mast's pan limits) -> trn_mast_point_at -> MAST_CMD until MAST_STATUS
 * says in position -> trigger pulse on the GPIO line (the simulator samples
 * the gpio-sim side and exposes at the rising edge) -> CAPTURE_CMD ->
 * capture over the kernel's ISO-TP socket into trn_capture_rx_segment ->
 * trn_mast_camera_to_map with the angles at exposure -> trn_mast_local_dem_mean
 * -> trn_localize_dem in a +-1.5 m window around the believed position ->
 * error against the true position and the predicted sigma.
 *
 * Criterion (docs/architecture.md, "the loop"): every run localizes
 * (TRN_OK), and the error is within 3 sigma per axis, sigma = the
 * localization's predicted sigma (eq. 6) combined with the half-cell
 * quantization floor (cell / sqrt(12)) in quadrature.
 *
 * The first run also records the bus with `candump -l` (can-utils, in the
 * VM's /usr/bin when the host has it) from just before the capture command
 * to the end of the capture, prints the log as KT-CANLOG lines (kept as
 * tests/data/can/sim_capture.log) and counts the capture's frames and bytes.
 */
#include <dirent.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ktest.h"
#include "rover_link.h"
#include "selworld.h"
#include "simrun.h"
#include "synth.h"
#include "trn/trn.h"

enum { N = 192, SIM_N = 384, L = 128, RUNS = 5 };
static const double CELL = 0.1;
static const char *ifname;
static float g_gdem[N * N];
static float g_simdem[SIM_N * SIM_N];
static float g_ldem[L * L];
static uint32_t g_lcnt[L * L];
static synth_rock_t g_rocks[2000];
static synth_terrain_t g_terr;
static selworld_t g_w;
static rover_link_t g_rover;
static trn_capture_t g_cap;
static trn_vec3f_t g_pts[TRN_PORT_MAX_CAPTURE_POINTS];

static uint64_t g_rs = 0x5EEDull;
static double unit(void) /* splitmix64, [0, 1) */
{
    uint64_t z = (g_rs += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

/* candump -l in /tmp as a child; returns its pid */
static pid_t candump_start(void)
{
    pid_t pid = fork();
    if (pid == 0) {
        if (chdir("/tmp") != 0) {
            _exit(127);
        }
        execl("/usr/bin/candump", "candump", "-l", ifname, (char *)NULL);
        _exit(127);
    }
    KT_CHECK(rover_idle(&g_rover, 200u) == ROVER_OK); /* candump is up; the link stays serviced */
    return pid;
}

/* stop candump, print its log, count the capture's frames */
static void candump_stop(pid_t pid, uint16_t cap_id)
{
    DIR *d;
    struct dirent *e;
    char path[300] = "";
    char line[256];
    FILE *f;
    int wst = 0;
    unsigned data_frames = 0, data_bytes = 0, fc_frames = 0, other = 0, lines = 0;
    double t_first = -1.0, t_last = -1.0;
    (void)cap_id;
    KT_CHECK(rover_idle(&g_rover, 100u) == ROVER_OK);
    kill(pid, SIGINT);
    KT_CHECK(waitpid(pid, &wst, 0) == pid);
    d = opendir("/tmp");
    KT_CHECK(d != NULL);
    if (d == NULL) {
        return;
    }
    while ((e = readdir(d)) != NULL) {
        if (strncmp(e->d_name, "candump-", 8) == 0) {
            snprintf(path, sizeof path, "/tmp/%s", e->d_name);
        }
    }
    closedir(d);
    KT_CHECK(path[0] != '\0');
    f = path[0] != '\0' ? fopen(path, "r") : NULL;
    KT_CHECK(f != NULL);
    if (f == NULL) {
        return;
    }
    while (fgets(line, sizeof line, f) != NULL) {
        double t = 0.0;
        char ifn[32], frame[64];
        unsigned id = 0;
        char *hash, *end;
        line[strcspn(line, "\r\n")] = '\0';
        printf("KT-CANLOG %s\n", line);
        ++lines;
        /* "(time) ifname id#data" */
        if (line[0] != '(') {
            continue;
        }
        t = strtod(line + 1, &end);
        if (end == line + 1 || *end != ')' || sscanf(end + 1, "%31s %63s", ifn, frame) != 2 ||
            (hash = strchr(frame, '#')) == NULL) {
            continue;
        }
        id = (unsigned)strtoul(frame, NULL, 16);
        if (id == 0x1A0u) {
            ++data_frames;
            data_bytes += (unsigned)(strlen(hash + 1) / 2u);
            if (t_first < 0.0) {
                t_first = t;
            }
            t_last = t;
        } else if (id == 0x1A1u) {
            ++fc_frames;
        } else {
            ++other;
        }
    }
    fclose(f);
    printf(
        "KT-INFO candump: %u lines; capture: %u data frames (0x1A0), %u data-field bytes, %u flow "
        "controls (0x1A1, 3 bytes each), %u other frames, %.3f s from first to last data frame\n",
        lines, data_frames, data_bytes, fc_frames, other, t_last - t_first);
    KT_CHECK(data_frames > 0u && fc_frames > 0u);
}

typedef struct {
    int ok;
    double err_x_m, err_y_m;         /* estimate - truth */
    double sig_x_m, sig_y_m;         /* localization's predicted sigma (eq. 6) */
    double sel_sig_x_m, sel_sig_y_m; /* the selection's prediction for the target */
    double range_m;
    unsigned points, used;
} loop_result_t;

/* One run of the loop; record = 1 also records the capture with candump. */
static loop_result_t one_run(int run, int record)
{
    loop_result_t out;
    sim_cfg_t sc;
    simrun_t sim;
    rover_cfg_t rc;
    trn_rover_pose_t truth, believed, known;
    trn_select_cfg_t scfg;
    trn_rover_t rv;
    trn_select_result_t sres;
    trn_candidate_t *cands;
    size_t cap, ranked[4], wsb, npts = 0u, used = 0u;
    void *ws;
    trn_vec3f_t target;
    float pan = 0.0f, tilt = 0.0f;
    trn_mast_status_t at;
    trn_cap_err_t ce = TRN_CAP_ERR_NONE;
    trn_rigid_t T;
    trn_grid_f32_t lg;
    trn_local_dem_cfg_t dcfg;
    trn_window_t win;
    trn_loc_result_t res;
    trn_status_t st;
    pid_t dump = -1;
    int32_t bx, by;
    memset(&out, 0, sizeof out);

    /* truth and belief */
    truth.x_m = (float)(8.0 + 3.0 * unit());
    truth.y_m = (float)(8.0 + 3.0 * unit());
    truth.heading_rad = (float)(-3.0 + 6.0 * unit());
    truth.z_m = (float)synth_height(&g_terr, truth.x_m, truth.y_m);
    believed = truth;
    believed.x_m += (float)(-0.8 + 1.6 * unit());
    believed.y_m += (float)(-0.8 + 1.6 * unit());
    bx = (int32_t)lround(believed.x_m / CELL);
    by = (int32_t)lround(believed.y_m / CELL);
    believed.z_m = g_gdem[by * N + bx];

    /* select the target from the believed position (paper section 4) */
    trn_select_cfg_default(&scfg);
    scfg.min_range_m = 2.0f;
    scfg.max_range_m = 4.5f;
    {
        /* only targets the mast can reach: its pan limits, less a margin for
         * the camera's offset from the pan axis */
        sim_cfg_t d;
        sim_cfg_default(&d);
        scfg.pan_min_rad = d.geom.pan_min_rad + 0.1f;
        scfg.pan_max_rad = d.geom.pan_max_rad - 0.1f;
    }
    rv.pos.x_cells = (float)(believed.x_m / CELL);
    rv.pos.y_cells = (float)(believed.y_m / CELL);
    rv.heading_rad = believed.heading_rad;
    cap = trn_select_max_candidates(&scfg, (float)CELL);
    cands = (trn_candidate_t *)malloc(cap * sizeof *cands);
    wsb = trn_select_workspace_bytes(&scfg, &g_w.map, &g_w.k);
    ws = selworld_alloc(wsb);
    KT_CHECK(cands != NULL && ws != NULL);
    if (cands == NULL || ws == NULL) {
        free(cands);
        free(ws);
        return out;
    }
    KT_ST(trn_select(&g_w.map, &g_w.k, &g_w.pg, &scfg, &rv, cands, cap, ranked, 4, &sres, ws, wsb),
          TRN_OK);
    free(ws);
    target.x = (float)(cands[ranked[0]].x * CELL);
    target.y = (float)(cands[ranked[0]].y * CELL);
    target.z = g_gdem[cands[ranked[0]].y * N + cands[ranked[0]].x];
    out.sel_sig_x_m = cands[ranked[0]].sigma_x_m;
    out.sel_sig_y_m = cands[ranked[0]].sigma_y_m;
    out.range_m = cands[ranked[0]].range_m;
    free(cands);

    /* simulator: the truth */
    sim_cfg_default(&sc);
    sc.ifname = ifname;
    sc.dem.heights = g_simdem;
    sc.dem.width = SIM_N;
    sc.dem.height = SIM_N;
    sc.dem.cell_m = (float)(CELL / 2.0);
    sc.pose = truth;
    sc.seed = 100u + (uint64_t)run;
    sc.trigger_path = NULL;
    {
        static char trig[300];
        snprintf(trig, sizeof trig, "%s/sim_gpio1/value", kt_env("TRN_GPIO_SIM", "/nonexistent"));
        sc.trigger_path = trig;
    }
    sc.run_ms = 60000u;
    KT_CHECK(simrun_start(&sim, &sc) == 0);

    /* rover */
    rover_cfg_default(&rc);
    rc.ifname = ifname;
    rc.gpio_chip = kt_env("TRN_GPIO_CHIP", "gpiochip0");
    KT_ST(rover_open(&g_rover, &rc), TRN_OK);
    KT_CHECK(rover_wait_alive(&g_rover) == ROVER_OK);
    KT_ST(trn_mast_point_at(&sc.geom, &believed, &target, &pan, &tilt), TRN_OK);
    KT_CHECK(rover_point(&g_rover, pan, tilt, &at) == ROVER_OK);
    if (record) {
        dump = candump_start();
    }
    {
        rover_outcome_t o = rover_capture(&g_rover, (uint16_t)(0x100 + run), 0u, &g_cap, &ce);
        KT_CHECK(o == ROVER_OK);
        if (o != ROVER_OK) {
            printf("KT-INFO capture: outcome %s, capture error %s, transport %s\n",
                   rover_outcome_name(o), trn_cap_err_name(ce),
                   trn_strerror(g_rover.last_transport));
        }
    }
    if (record) {
        candump_stop(dump, (uint16_t)(0x100 + run));
    }
    /* the link stayed healthy: no silence, no lost heartbeat */
    KT_CHECK(g_rover.mast_hb.n_silences == 0u && g_rover.stereo_hb.n_silences == 0u);
    KT_CHECK(g_rover.mast_hb.n_gaps == 0u && g_rover.stereo_hb.n_gaps == 0u);
    rover_close(&g_rover);
    KT_CHECK(simrun_stop(&sim) == 0);
    KT_CHECK(sim.stats.triggers == 1u && sim.stats.triggered_exposures == 1u);
    KT_CHECK(g_cap.capture_id == (uint16_t)(0x100 + run));
    KT_CHECK(g_cap.pan_100urad == at.pan_100urad && g_cap.tilt_100urad == at.tilt_100urad);
    KT_CHECK(g_cap.mast_faults == 0u && !(g_cap.mast_state & TRN_MAST_ST_MOVING));
    out.points = g_cap.n_points;

    /* to the map, local DEM, localize */
    known = believed;
    known.x_m =
        0.0f; /* the local map is built around the rover: only heading and height are used */
    known.y_m = 0.0f;
    KT_ST(trn_capture_points_m(&g_cap, g_pts, TRN_PORT_MAX_CAPTURE_POINTS, &npts), TRN_OK);
    KT_ST(trn_mast_camera_to_map(&sc.geom, &known, trn_can_angle_from_raw(g_cap.pan_100urad),
                                 trn_can_angle_from_raw(g_cap.tilt_100urad), &T),
          TRN_OK);
    KT_ST(trn_rigid_apply(&T, g_pts, npts, g_pts), TRN_OK);
    dcfg.cell_m = (float)CELL;
    dcfg.rover_col = L / 2;
    dcfg.rover_row = L / 2;
    dcfg.row_north = 1;
    KT_ST(trn_grid_f32_init(&lg, g_ldem, (size_t)L * L, L, L), TRN_OK);
    /* each cell the mean of its points (the highest point biases the map
     * toward the rover: tests/test_sim_loop.c) */
    KT_ST(trn_mast_local_dem_mean(g_pts, npts, &known, &dcfg, &lg, g_lcnt, (size_t)L * L, &used),
          TRN_OK);
    out.used = (unsigned)used;
    win.x0 = bx - 15;
    win.x1 = bx + 15;
    win.y0 = by - 15;
    win.y1 = by + 15;
    wsb = trn_localize_dem_workspace_bytes(&g_w.map, L, L, (size_t)L * L * g_w.cfg.terrain.nz,
                                           &win);
    ws = selworld_alloc(wsb);
    KT_CHECK(ws != NULL);
    if (ws == NULL) {
        return out;
    }
    st = trn_localize_dem(&g_w.map, &lg, L / 2, L / 2, (size_t)L * L * g_w.cfg.terrain.nz, &win, ws,
                          wsb, &res);
    free(ws);
    KT_ST(st, TRN_OK);
    out.ok = st == TRN_OK;
    out.err_x_m = res.x * CELL - truth.x_m;
    out.err_y_m = res.y * CELL - truth.y_m;
    out.sig_x_m = res.sigma_x_m;
    out.sig_y_m = res.sigma_y_m;
    printf("KT-INFO loop run %d: truth (%.3f, %.3f) hdg %.2f, prior offset (%+.2f, %+.2f) m, "
           "target range "
           "%.2f m pan %.4f tilt %.4f, %u points (%u used), estimate (%.3f, %.3f): error (%+.3f, "
           "%+.3f) m, "
           "predicted sigma (%.3f, %.3f) m, selection predicted (%.3f, %.3f) m, P_fail %.3g\n",
           run, truth.x_m, truth.y_m, truth.heading_rad, believed.x_m - truth.x_m,
           believed.y_m - truth.y_m, out.range_m, pan, tilt, out.points, out.used, res.x * CELL,
           res.y * CELL, out.err_x_m, out.err_y_m, out.sig_x_m, out.sig_y_m, out.sel_sig_x_m,
           out.sel_sig_y_m, res.failure_probability);
    return out;
}

static void whole_loop(void)
{
    int run;
    const double floor_m = CELL / sqrt(12.0);
    double se = 0.0;
    for (run = 0; run < RUNS; ++run) {
        loop_result_t r = one_run(run, run == 0);
        double sx = sqrt(r.sig_x_m * r.sig_x_m + floor_m * floor_m);
        double sy = sqrt(r.sig_y_m * r.sig_y_m + floor_m * floor_m);
        KT_CHECK(r.ok);
        KT_CHECK(fabs(r.err_x_m) <= 3.0 * sx);
        KT_CHECK(fabs(r.err_y_m) <= 3.0 * sy);
        printf(
            "KT-INFO loop run %d: |error| / sigma = %.2f (x), %.2f (y) with sigma = predicted (+) "
            "cell/sqrt(12); %.2f, %.2f against the predicted sigma alone\n",
            run, fabs(r.err_x_m) / sx, fabs(r.err_y_m) / sy, fabs(r.err_x_m) / r.sig_x_m,
            fabs(r.err_y_m) / r.sig_y_m);
        se += r.err_x_m * r.err_x_m + r.err_y_m * r.err_y_m;
    }
    printf("KT-INFO loop: RMS position error over %d runs %.3f m\n", RUNS, sqrt(se / RUNS));
}

int main(void)
{
    trn_sigma_model_t gm;
    trn_xy_t sensor = {N / 2.0f, N / 2.0f};
    size_t nrocks = (size_t)(N * N * CELL * CELL * 0.15 / (3.14159265 * 0.15 * 0.15));
    trn_status_t st;
    ifname = kt_env("TRN_CAN_IF", "vcan0");
    synth_make(&g_terr, g_rocks, nrocks, N * CELL, 0.05, 0.3, 0.5, 0.2, 12u);
    synth_render(&g_terr, g_gdem, N, N, 0.0, 0.0, CELL);
    synth_render(&g_terr, g_simdem, SIM_N, SIM_N, 0.0, 0.0, CELL / 2.0);
    trn_sigma_global_default(&gm);
    st = selworld_init(&g_w, N, g_gdem, &gm, &sensor, 1u);
    KT_ST(st, TRN_OK);
    if (st == TRN_OK) {
        KT_RUN(whole_loop);
    }
    selworld_free(&g_w);
    return kt_finish("kt_loop");
}
