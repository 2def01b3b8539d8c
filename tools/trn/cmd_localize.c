/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/cmd_localize.c - `trn localize`: the maximum-likelihood rover
 * position of a local DEM (rover frame) in a global DEM (map frame).
 *
 * Frames. Map: x east, y north, metres (the global DEM's geotransform).
 * Rover frame: the local DEM's geotransform gives metres relative to the
 * rover, x east, y north, the rover at (0, 0) (heading known, paper section
 * 2). The core works in global cells with y = row (south); the local DEM is
 * handed over with the rover's nearest local cell (rx, ry) as its origin, and
 * the core's pose is where that cell's centre lands in the global grid. The
 * rover's map position is that point minus the cell centre's offset from the
 * rover. */
#define _POSIX_C_SOURCE 200112L /* clock_gettime */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "cmd_run.h"
#include "commands.h"
#include "dem_io.h"
#include "mapopt.h"
#include "trn/trn.h"

/* 16-byte aligned block; free with free(raw). */
static void *alloc16(size_t n, void **raw)
{
    uint8_t *p = malloc(n + 16u);
    *raw = p;
    if (p == NULL) {
        return NULL;
    }
    return p + ((16u - ((uintptr_t)p & 15u)) & 15u);
}

static const char *status_word(trn_status_t st)
{
    return st == TRN_OK            ? "ok"
           : st == TRN_E_ILLCOND   ? "ill_conditioned"
           : st == TRN_E_AMBIGUOUS ? "ambiguous"
                                   : "error";
}

static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e3 + (double)t.tv_nsec * 1e-6;
}

/* The (x, y, heading) search of one case (the local DEM lg, rover cell rx, ry):
 * o->res from its position part, the heading and the 3 x 3 covariance in
 * (east m, north m, heading deg). Returns the core's status. */
static trn_status_t localize_heading(const cmd_localize_ctx_t *c, const trn_grid_f32_t *lg, int rx,
                                     int ry, size_t max_pts, const trn_window_t *win,
                                     cmd_localize_out_t *o)
{
    const double deg = 180.0 / 3.14159265358979323846;
    const trn_heading_cfg_t hc = {c->heading_deg / deg, c->heading_win_deg / deg, 0.0};
    const double sgn[3] = {1.0, -1.0,
                           deg}; /* core rows point south: flip north terms; radians to degrees */
    trn_heading_result_t hr;
    size_t wb = trn_localize_dem_heading_workspace_bytes_cfg(&c->map, lg, rx, ry, max_pts, win,
                                                             &hc);
    void *raw = NULL, *ws = wb > 0 ? alloc16(wb, &raw) : NULL;
    trn_status_t st;
    int i;
    if (ws == NULL) {
        return TRN_E_WORKSPACE;
    }
    memset(&hr, 0, sizeof hr); /* nothing unset reaches the JSON on an early error */
    st = trn_localize_dem_heading(&c->map, lg, rx, ry, max_pts, win, &hc, ws, wb, &hr);
    free(raw);
    o->res = hr.loc;
    o->heading_deg = hr.heading_rad * deg;
    o->sigma_heading_deg = hr.sigma_heading_rad * deg;
    for (i = 0; i < 9; ++i) {
        const double v = hr.cov3[i] * sgn[i / 3] * sgn[i % 3];
        o->cov3[i] = v == 0.0 ? 0.0 : v;
    }
    return st;
}

/* The local DEM l against the context: sizes and the cell size. 0, or -1 with the reason. */
static int check_local(const cmd_localize_ctx_t *c, const dem_t *l, char *err, size_t err_len)
{
    double cell = c->g.cell_m;
    if (l->width > c->max_local || l->height > c->max_local) {
        snprintf(err, err_len, "--local is %d x %d cells, larger than --max-local-cells %ld",
                 l->width, l->height, c->max_local);
        return -1;
    }
    if (l->width > c->g.width || l->height > c->g.height) {
        snprintf(err, err_len, "--local (%d x %d cells) is larger than --dem (%d x %d cells)",
                 l->width, l->height, c->g.width, c->g.height);
        return -1;
    }
    if (fabs(l->cell_m - cell) > 1e-6 * cell) {
        snprintf(err, err_len,
                 "cell sizes differ: --dem %g m, --local %g m (resample the local DEM to %g m, "
                 "e.g. gdalwarp -tr %g %g -r bilinear)",
                 cell, l->cell_m, cell, cell, cell);
        return -1;
    }
    return 0;
}

/* The rover's nearest local cell (rx, ry), the offset (dx_m, dy_m) of its
 * centre from the rover, and the window of its poses around prior, clipped to
 * the map (o->radius). 0, or -1 with the reason. */
static int case_window(const cmd_localize_ctx_t *c, const dem_t *l, const double prior[2],
                       double window_m, int *rx, int *ry, double *dx_m, double *dy_m,
                       trn_window_t *win, cmd_localize_out_t *o, char *err, size_t err_len)
{
    double cell = c->g.cell_m, rcol, rrow, pc, pr;
    int pcol, prow;
    /* The rover (0, 0 in the rover frame) in the local grid. */
    dem_map_to_cell(l->gt, 0.0, 0.0, &rcol, &rrow);
    if (fabs(rcol) > (double)TRN_MAX_DIM || fabs(rrow) > (double)TRN_MAX_DIM) {
        snprintf(
            err, err_len,
            "--local: the rover (0,0 of its geotransform) is %.0f, %.0f cells from the grid; is it "
            "in the rover frame?",
            rcol, rrow);
        return -1;
    }
    *rx = (int)floor(rcol + 0.5);
    *ry = (int)floor(rrow + 0.5);
    /* Offset of that local cell's centre from the rover, map metres. */
    dem_cell_to_map(l->gt, (double)*rx, (double)*ry, dx_m, dy_m);
    if (!dem_cell_of(&c->g, prior[0], prior[1], &pcol, &prow)) {
        snprintf(err, err_len, "--prior %.3f,%.3f is off the map (x %.3f..%.3f, y %.3f..%.3f)",
                 prior[0], prior[1], c->g.gt[0], c->g.gt[0] + c->g.width * cell,
                 c->g.gt[3] - c->g.height * cell, c->g.gt[3]);
        return -1;
    }
    o->radius = (long)ceil(window_m / cell - 1e-9);
    if (o->radius > TRN_MAX_DIM) {
        snprintf(err, err_len, "--window-m %g is %ld cells, more than the %d the core searches",
                 window_m, o->radius, TRN_MAX_DIM);
        return -1;
    }
    /* Window of poses of the local cell (rx, ry), clipped to the map. */
    dem_map_to_cell(c->g.gt, prior[0] + *dx_m, prior[1] + *dy_m, &pc, &pr);
    pcol = (int)floor(pc + 0.5);
    prow = (int)floor(pr + 0.5);
    win->x0 = (int32_t)(pcol - o->radius < 0 ? 0 : pcol - o->radius);
    win->y0 = (int32_t)(prow - o->radius < 0 ? 0 : prow - o->radius);
    win->x1 = (int32_t)(pcol + o->radius > c->g.width - 1 ? c->g.width - 1 : pcol + o->radius);
    win->y1 = (int32_t)(prow + o->radius > c->g.height - 1 ? c->g.height - 1 : prow + o->radius);
    if (win->x0 > win->x1 || win->y0 > win->y1) {
        snprintf(err, err_len, "the searched window around --prior lies off the map");
        return -1;
    }
    return 0;
}

/* Pose (global cells, y = row = south) -> rover position (map, y north); the
 * core's row axis points south: flip the correlation's sign (no -0). */
static void case_to_map(const cmd_localize_ctx_t *c, double dx_m, double dy_m,
                        cmd_localize_out_t *o)
{
    double ex, ey;
    dem_cell_to_map(c->g.gt, o->res.x, o->res.y, &ex, &ey);
    o->x_m = ex - dx_m;
    o->y_m = ey - dy_m;
    o->rho_en = isfinite(o->res.rho) && o->res.rho != 0.0 ? -o->res.rho
                : o->res.rho == 0.0                       ? 0.0
                                                          : o->res.rho;
    o->cov_en[0] = o->res.cov_m2[0];
    o->cov_en[1] = o->res.cov_m2[1];
    o->cov_en[2] = o->res.cov_m2[2] != 0.0 ? -o->res.cov_m2[2] : 0.0;
}

/* Band `band` of the local DEM file path into out, on the same grid as the
 * heights l (opt: the option that names it, for the reason). 0, or -1 with
 * the reason (out freed). */
static int read_cell_band(const char *path, long band, const char *opt, const dem_t *l, dem_t *out,
                          char *err, size_t err_len)
{
    char why[512];
    if (dem_read(path, (int)band, TRN_MAX_DIM, out, why, sizeof why) != 0) {
        snprintf(err, err_len, "%s: %s", opt, why);
        return -1;
    }
    if (out->width != l->width || out->height != l->height) {
        snprintf(err, err_len, "%s: band %ld is %d x %d cells, the heights %d x %d", opt, band,
                 out->width, out->height, l->width, l->height);
        dem_free(out);
        return -1;
    }
    return 0;
}

/* The centroid bands (--centroid-bands N) of the local DEM l read from
 * path into cen[0] (east) and cen[1] (south): the same grid as l, and for
 * every seen cell finite and within TRN_CENTROID_MAX. 0, or -1 with the
 * reason (cen freed). */
static int read_centroids(const cmd_localize_ctx_t *c, const char *path, const dem_t *l,
                          dem_t cen[2], char *err, size_t err_len)
{
    int k;
    size_t i, n = (size_t)l->width * (size_t)l->height;
    for (k = 0; k < 2; ++k) {
        if (read_cell_band(path, c->centroid_band + k, "--centroid-bands", l, &cen[k], err,
                           err_len) != 0) {
            goto bad;
        }
    }
    for (i = 0; i < n; ++i) {
        if (isfinite(l->data[i]) && !(fabsf(cen[0].data[i]) <= (float)TRN_CENTROID_MAX &&
                                      fabsf(cen[1].data[i]) <= (float)TRN_CENTROID_MAX)) {
            snprintf(err, err_len,
                     "--centroid-bands: local cell (%zu, %zu) is seen but its centroid (%g, %g) is "
                     "missing or more than %g cells from its centre",
                     i % (size_t)l->width, i / (size_t)l->width, (double)cen[0].data[i],
                     (double)cen[1].data[i], TRN_CENTROID_MAX);
            goto bad;
        }
    }
    return 0;
bad:
    dem_free(&cen[0]);
    dem_free(&cen[1]);
    return -1;
}

/* The count band (--count-band N) of the local DEM l read from path into
 * cnt: the same grid as l, and for every seen cell a finite count within
 * [1, TRN_POINT_COUNT_MAX]. 0, or -1 with the reason (cnt freed). */
static int read_counts(const cmd_localize_ctx_t *c, const char *path, const dem_t *l, dem_t *cnt,
                       char *err, size_t err_len)
{
    size_t i, n = (size_t)l->width * (size_t)l->height;
    if (read_cell_band(path, c->count_band, "--count-band", l, cnt, err, err_len) != 0) {
        return -1;
    }
    for (i = 0; i < n; ++i) {
        if (isfinite(l->data[i]) &&
            !(cnt->data[i] >= 1.0f && (double)cnt->data[i] <= TRN_POINT_COUNT_MAX)) {
            snprintf(err, err_len,
                     "--count-band: local cell (%zu, %zu) is seen but its point count %g is "
                     "missing or outside [1, %g]",
                     i % (size_t)l->width, i / (size_t)l->width, (double)cnt->data[i],
                     TRN_POINT_COUNT_MAX);
            dem_free(cnt);
            return -1;
        }
    }
    return 0;
}

int cmd_localize_run(const cmd_localize_ctx_t *c, const char *local_path, const double prior[2],
                     double window_m, cmd_localize_out_t *o, char *err, size_t err_len)
{
    dem_t l, cen[2], cnt;
    trn_local_cells_t cells;
    double dx_m, dy_m, t0;
    int rx, ry, rc = CLI_BAD_INPUT;
    trn_grid_f32_t lg;
    trn_window_t win;
    size_t wb, max_pts;
    void *wraw = NULL, *ws;

    memset(o, 0, sizeof *o);
    memset(cen, 0, sizeof cen);
    memset(&cnt, 0, sizeof cnt);
    if (dem_read(local_path, (int)c->local_band, TRN_MAX_DIM, &l, err, err_len) != 0) {
        return CLI_BAD_INPUT;
    }
    if (check_local(c, &l, err, err_len) != 0 ||
        (c->centroid_band > 0 && read_centroids(c, local_path, &l, cen, err, err_len) != 0) ||
        (c->count_band > 0 && read_counts(c, local_path, &l, &cnt, err, err_len) != 0) ||
        case_window(c, &l, prior, window_m, &rx, &ry, &dx_m, &dy_m, &win, o, err, err_len) != 0) {
        goto done;
    }
    if (trn_grid_f32_init(&lg, l.data, (size_t)l.width * (size_t)l.height, l.width, l.height) !=
        TRN_OK) {
        snprintf(err, err_len, "local DEM size rejected by the core");
        goto done;
    }
    max_pts = (size_t)l.width * (size_t)l.height * (size_t)c->cfg.terrain.nz;
    wb = trn_localize_dem_workspace_bytes(&c->map, l.width, l.height, max_pts, &win);
    ws = wb > 0 ? alloc16(wb, &wraw) : NULL;
    if (ws == NULL) {
        snprintf(err, err_len, "cannot allocate %zu bytes of localization workspace", wb);
        goto done;
    }
    t0 = now_ms();
    if (c->heading) {
        o->st = localize_heading(c, &lg, rx, ry, max_pts, &win, o);
    } else {
        cells.centroid_x = cen[0].data;
        cells.centroid_y = cen[1].data;
        cells.point_count = cnt.data;
        o->st = trn_localize_dem_cells(&c->map, &lg, &cells, rx, ry, max_pts, &win, ws, wb,
                                       &o->res);
    }
    o->time_ms = now_ms() - t0;
    if (o->st != TRN_OK && o->st != TRN_E_ILLCOND && o->st != TRN_E_AMBIGUOUS) {
        snprintf(err, err_len, "localization failed: %s", trn_strerror(o->st));
        goto done;
    }
    case_to_map(c, dx_m, dy_m, o);
    rc = CLI_OK;
done:
    free(wraw);
    dem_free(&l);
    dem_free(&cen[0]);
    dem_free(&cen[1]);
    dem_free(&cnt);
    return rc;
}

void cmd_localize_report_json(FILE *out, const cmd_localize_ctx_t *c, const char *local,
                              const double prior[2], double window_m, const cmd_localize_out_t *o,
                              int batch)
{
    json_t j;
    json_begin(&j, out);
    json_num(&j, "x_m", o->x_m);
    json_num(&j, "y_m", o->y_m);
    json_num(&j, "sigma_x_m", o->res.sigma_x_m);
    json_num(&j, "sigma_y_m", o->res.sigma_y_m);
    json_num(&j, "rho", o->rho_en);
    json_arr(&j, "cov_m2");
    json_num(&j, NULL, o->cov_en[0]);
    json_num(&j, NULL, o->cov_en[1]);
    json_num(&j, NULL, o->cov_en[2]);
    json_arr_end(&j);
    json_num(&j, "failure_probability", o->res.failure_probability);
    if (c->heading) {
        int i;
        json_num(&j, "heading_deg", o->heading_deg);
        json_num(&j, "sigma_heading_deg", o->sigma_heading_deg);
        json_arr(&j, "cov3");
        for (i = 0; i < 9; ++i) {
            json_num(&j, NULL, o->cov3[i]);
        }
        json_arr_end(&j);
    }
    json_str(&j, "status", status_word(o->st));
    json_bool(&j, "refined", o->res.refined != 0);
    json_bool(&j, "centroids", c->centroid_band > 0);
    json_bool(&j, "point_counts", c->count_band > 0);
    json_num(&j, "noise_scale", o->res.noise_scale);
    if (c->cfg.match == TRN_MATCH_HEIGHTS) {
        json_str(&j, "search",
                 c->heading || o->res.search == TRN_SEARCH_EXHAUSTIVE ? "exhaustive" : "bounded");
        json_num(&j, "failure_prob_bound", o->res.failure_prob_bound);
        json_int(&j, "blocks_bounded", (long long)o->res.stats.blocks_bounded);
    }
    if (o->res.refined) {
        /* the refinement's own figures (docs/method.md 9), grid frame: x
         * east, y south, cells */
        const trn_refine_t *rf = &o->res.refinement;
        json_obj(&j, "refinement");
        json_num(&j, "model_m", rf->model_m);
        json_num(&j, "chi2_dof", rf->chi2_dof);
        json_num(&j, "inflation", rf->inflation);
        json_num(&j, "ll_inflation", rf->ll_inflation);
        json_num(&j, "interp_mix", rf->interp_mix);
        json_num(&j, "shoulders", rf->shoulders);
        json_arr(&j, "spline_step_cells");
        json_num(&j, NULL, rf->spline_step[0]);
        json_num(&j, NULL, rf->spline_step[1]);
        json_arr_end(&j);
        json_int(&j, "points_used", (long long)rf->n_used);
        json_int(&j, "iterations", (long long)rf->iterations);
        json_num(&j, "log_likelihood", rf->ll);
        if (c->cfg.match == TRN_MATCH_HEIGHTS) {
            /* the relief test (misfit below -TRN_RELIEF_Z; null: not tested) */
            json_num(&j, "relief_z", o->res.relief_z);
            json_bool(&j, "misfit", o->res.misfit != 0);
        }
        json_obj_end(&j);
    }
    json_obj(&j, "prior");
    json_num(&j, "x_m", prior[0]);
    json_num(&j, "y_m", prior[1]);
    json_obj_end(&j);
    json_num(&j, "window_m", window_m);
    json_num(&j, "cell_m", c->g.cell_m);
    json_bool(&j, "on_window_edge", o->res.on_window_edge != 0);
    json_int(&j, "local_points", (long long)o->res.n_points);
    json_num(&j, "log_likelihood", o->res.ll_best);
    json_int(&j, "poses_scored", (long long)o->res.stats.poses_scored);
    json_num(&j, "time_ms", o->time_ms);
    if (batch) {
        json_str(&j, "local", local);
    } else {
        mapopt_json(&j, &c->cfg);
    }
    json_end(&j);
}

/* The fields of a --batch line, "LOCAL PRIOR_X PRIOR_Y [WINDOW_M]": the path
 * into local (at most cap - 1 characters), each number by cli_parse_double
 * (a number out of range or not finite makes the line bad). Returns how
 * many fields were read, 5 if there are more than four, 0 for a bad one. */
static int batch_fields(const char *line, char *local, size_t cap, double prior[2], double *w)
{
    const char *p = line;
    double *dst[3];
    int n;
    dst[0] = &prior[0];
    dst[1] = &prior[1];
    dst[2] = w;
    for (n = 0; n < 5; ++n) {
        char tok[128];
        char *out = n == 0 ? local : tok; /* the path, then each number's text */
        size_t room = n == 0 ? cap : sizeof tok, len;
        p += strspn(p, " \t\r\n");
        len = strcspn(p, " \t\r\n");
        if (len == 0) {
            return n;
        }
        if (n == 4) {
            return 5;
        }
        if (len >= room) {
            return 0;
        }
        memcpy(out, p, len);
        out[len] = '\0';
        if (n > 0 && !cli_parse_double(tok, dst[n - 1])) {
            return 0;
        }
        p += len;
    }
    return n;
}

/* --batch: one case per line, "LOCAL PRIOR_X PRIOR_Y [WINDOW_M]"; blank
 * lines and lines starting with # are skipped. A case that cannot be
 * localized prints {"status": "error", "error": ...} and the run goes on;
 * a malformed line stops it (exit 1). */
static int run_batch(const cmd_localize_ctx_t *c, const char *path, double window_m)
{
    FILE *f = fopen(path, "r");
    char line[4096], local[4096], err[CMD_ERR_LEN];
    long lineno = 0;
    if (f == NULL) {
        return cli_fail("localize", "--batch %s: cannot open", path);
    }
    while (fgets(line, sizeof line, f) != NULL) {
        double prior[2], w = window_m;
        int nf;
        cmd_localize_out_t o;
        ++lineno;
        if (line[0] == '#' || strspn(line, " \t\r\n") == strlen(line)) {
            continue;
        }
        nf = batch_fields(line, local, sizeof local, prior, &w);
        if (nf < 3 || nf > 4 || !isfinite(prior[0]) || !isfinite(prior[1]) ||
            !(w >= 0.0 && w <= 1e6)) {
            fclose(f);
            return cli_fail("localize",
                            "--batch %s line %ld: expected 'LOCAL PRIOR_X PRIOR_Y [WINDOW_M]'",
                            path, lineno);
        }
        if (cmd_localize_run(c, local, prior, w, &o, err, sizeof err) != CLI_OK) {
            json_t j;
            json_begin(&j, stdout);
            json_str(&j, "status", "error");
            json_str(&j, "error", err);
            json_str(&j, "local", local);
            json_end(&j);
            continue;
        }
        cmd_localize_report_json(stdout, c, local, prior, w, &o, 1);
    }
    fclose(f);
    return 0;
}

void cmd_localize_params_default(cmd_localize_params_t *p)
{
    memset(p, 0, sizeof *p);
    p->window_m = 2.5;
    p->band = 1;
    p->local_band = 1;
    p->max_local = 1024;
    mapopt_init(&p->mo);
}

/* A map option the configured matcher does not read is refused (mapopt_check_use). */
static int localize_check_use(const cmd_localize_params_t *p)
{
    char err[512];
    if (mapopt_check_use(&p->mo, MAPOPT_USE_LOCALIZE, err, sizeof err) != 0) {
        fprintf(cli_message_stream(), "trn localize: %s\n", err);
        return CLI_USAGE;
    }
    return CLI_OK;
}

int cmd_localize_parse(int argc, char **argv, cmd_localize_params_t *p)
{
    cli_opt_t opts[13 + MAPOPT_N] = {
        {"--dem", CLI_STRING, &p->dem_path, 0, 0, 1, "FILE",
         "global DEM (any GDAL raster; map frame)", 0},
        {"--local", CLI_STRING, &p->local_path, 0, 0, 0, "FILE",
         "local DEM in the rover frame (rover at 0,0; x east, y north)", 0},
        {"--prior", CLI_XY, p->prior, 0, 0, 0, "X,Y",
         "where the rover believes it is, map metres (no default: required without --batch)", 0},
        {"--batch", CLI_STRING, &p->batch_path, 0, 0, 0, "LIST",
         "many cases, one per line 'LOCAL PRIOR_X PRIOR_Y [WINDOW_M]': the map is prepared once, "
         "one JSON line per case",
         0},
        {"--window-m", CLI_DOUBLE, &p->window_m, 0.0, 1e6, 0, "R",
         "prior uncertainty searched: +-R metres per axis", 0},
        {"--band", CLI_LONG, &p->band, 1, 65535, 0, "N", "band of --dem", 0},
        {"--local-band", CLI_LONG, &p->local_band, 1, 65535, 0, "N", "band of --local", 0},
        {"--centroid-bands", CLI_LONG, &p->centroid_band, 1, 65534, 0, "N",
         "bands N and N+1 of --local hold each cell's centroid (of the stereo points binned "
         "into it), cells east and south of the cell's centre, |c| <= 0.5: the refinement "
         "reads the map there (default: the cells' centres; not with a heading search)",
         0},
        {"--count-band", CLI_LONG, &p->count_band, 1, 65535, 0, "N",
         "band N of --local holds each cell's point count n (how many stereo points its height "
         "is the mean of; >= 1 where seen): its noise is the noise model's over sqrt(n), and "
         "without --centroid-bands its points' unknown centroid is a position error of "
         "1 / (12 n) cells^2 (default: one measurement a cell; not with a heading search)",
         0},
        {"--max-local-cells", CLI_LONG, &p->max_local, 8, TRN_MAX_DIM, 0, "N",
         "largest local map side accepted, cells", 0},
        {"--heading-deg", CLI_DOUBLE, &p->heading_deg, -180.0, 180.0, 0, "H",
         "turn the local DEM by H degrees (counterclockwise) before matching: the believed "
         "heading's correction",
         0},
        {"--heading-window-deg", CLI_DOUBLE, &p->heading_win_deg, 0.0, 180.0, 0, "W",
         "also search the heading over H +- W degrees (step: one cell of arc at the local map's "
         "farthest point); the height matcher (the auto configuration) refines it, the voxel "
         "matcher needs --refine 0 (default: heading known)",
         0},
        {"--search", CLI_STRING, &p->search, 0, 0, 0, "exhaustive|bounded",
         "the height matcher's search over (x, y): exhaustive (every pose scored; default) or "
         "bounded (branch and bound: the same answer, the failure probability within "
         "failure_prob_bound; docs/method.md 9); the search over heading is exhaustive",
         0},
        {"--node-budget", CLI_LONG, &p->node_budget, 0, 2000000000L, 0, "N",
         "the height matcher gives up (exit 1, 'search node budget exhausted') beyond N pose "
         "scores (over heading: pose-heading scores; bounded: and block bounds): a hard bound "
         "on its time (default 0: none)",
         0},
    };
    cli_opt_t json_opt = {
        "--json", CLI_FLAG, &p->json, 0, 0, 0, NULL, "print one JSON object instead of the summary",
        0};
    cli_opt_t all[15 + MAPOPT_N];
    const size_t n_all = sizeof all / sizeof all[0];
    cli_cmd_t cmd = {
        "localize",
        "Localize a rover: match its local DEM against the global DEM (paper section 2).",
        "Both DEMs must have the same square cell size; heights in metres, no-data and NaN\n"
        "mean \"not seen\". Give --local and --prior, or --batch. The map configuration is\n"
        "chosen from the global DEM (--map-config auto, docs/method.md section 9); every\n"
        "part of it can be set. Output: x_m, y_m (map), sigma_x_m (east), sigma_y_m (north),\n"
        "rho (east-north), cov_m2 [var_east, var_north, cov_en], failure_probability,\n"
        "status (ok | ill_conditioned: no finite covariance, the height refinement\n"
        "found no consistent match, or the best pose lies on the window's edge\n"
        "(on_window_edge; the truth may lie beyond it: widen --window-m) | ambiguous:\n"
        "failure_probability above\n"
        "--max-failure-prob; both: treat as not localized), time_ms (the localization).",
        all, sizeof all / sizeof all[0]};
    int rc;

    memcpy(all, opts, 14 * sizeof opts[0]);
    mapopt_cli(&p->mo, all + 14);
    all[14 + MAPOPT_N] = json_opt;
    rc = cli_parse(&cmd, argc, argv);
    if (rc != CLI_OK) {
        return rc;
    }
    p->have_prior = cli_find(all, n_all, "--prior")->seen;
    p->heading = cli_find(all, n_all, "--heading-deg")->seen ||
                 cli_find(all, n_all, "--heading-window-deg")->seen;
    if (p->batch_path == NULL && (p->local_path == NULL || !p->have_prior)) {
        fprintf(cli_message_stream(),
                "trn localize: give --local FILE and --prior X,Y, or --batch LIST (see --help)\n");
        return CLI_USAGE;
    }
    if (p->batch_path != NULL && (p->local_path != NULL || p->have_prior)) {
        fprintf(cli_message_stream(), "trn localize: --batch replaces --local and --prior; give "
                                      "one or the other (see --help)\n");
        return CLI_USAGE;
    }
    if ((p->centroid_band > 0 || p->count_band > 0) && p->heading) {
        fprintf(cli_message_stream(),
                "trn localize: %s does not apply to a heading search or turn "
                "(--heading-deg, --heading-window-deg)\n",
                p->centroid_band > 0 ? "--centroid-bands" : "--count-band");
        return CLI_USAGE;
    }
    return localize_check_use(p);
}

int cmd_localize_prepare(const cmd_localize_params_t *p, cmd_localize_ctx_t *c, char *err,
                         size_t err_len)
{
    char why[768];
    trn_grid_f32_t gg;
    trn_status_t st;
    size_t mb;
    void *mbuf;

    memset(c, 0, sizeof *c);
    c->local_band = p->local_band;
    c->centroid_band = p->centroid_band;
    c->count_band = p->count_band;
    c->max_local = p->max_local;
    c->heading = p->heading;
    c->heading_deg = p->heading_deg;
    c->heading_win_deg = p->heading_win_deg;
    if (dem_read(p->dem_path, (int)p->band, TRN_MAX_DIM, &c->g, why, sizeof why) != 0) {
        snprintf(err, err_len, "--dem: %s", why);
        return CLI_BAD_INPUT;
    }
    if (mapopt_config(&p->mo, c->g.data, c->g.width, c->g.height, c->g.cell_m, &c->cfg, NULL, why,
                      sizeof why) != 0) {
        snprintf(err, err_len, "--dem: %s", why);
        return CLI_BAD_INPUT;
    }
    if (p->search != NULL && strcmp(p->search, "bounded") != 0 &&
        strcmp(p->search, "exhaustive") != 0) {
        snprintf(err, err_len, "--search must be bounded or exhaustive, not '%s'", p->search);
        return CLI_BAD_INPUT;
    }
    if ((p->search != NULL || p->node_budget > 0) && c->cfg.match != TRN_MATCH_HEIGHTS) {
        snprintf(err, err_len,
                 "--search and --node-budget shape the height matcher's search "
                 "(--match heights, the auto configuration), not the voxel matcher's");
        return CLI_BAD_INPUT;
    }
    if (p->search != NULL && strcmp(p->search, "bounded") == 0 && c->heading &&
        c->heading_win_deg > 0.0) {
        snprintf(err, err_len,
                 "--search bounded: the search over heading "
                 "(--heading-window-deg) is exhaustive only");
        return CLI_BAD_INPUT;
    }
    c->cfg.search = p->search != NULL && strcmp(p->search, "bounded") == 0 ? TRN_SEARCH_BOUNDED
                                                                           : TRN_SEARCH_EXHAUSTIVE;
    c->cfg.node_budget = (uint32_t)p->node_budget;
    if (c->heading && c->cfg.match == TRN_MATCH_VOXEL && c->cfg.refine != 0) {
        snprintf(err, err_len,
                 "--heading-deg/--heading-window-deg: the voxel matcher searches heading without "
                 "refinement only (--map-config paper, or --refine 0); the height matcher "
                 "(--match heights, the auto configuration) searches it with refinement");
        return CLI_BAD_INPUT;
    }
    if (trn_grid_f32_init(&gg, c->g.data, (size_t)c->g.width * (size_t)c->g.height, c->g.width,
                          c->g.height) != TRN_OK) {
        snprintf(err, err_len, "DEM sizes rejected by the core");
        return CLI_BAD_INPUT;
    }
    mb = trn_map_bytes(&c->cfg, c->g.width, c->g.height);
    mbuf = mb > 0 ? alloc16(mb, &c->mraw) : NULL;
    if (mbuf == NULL) {
        snprintf(err, err_len, "cannot allocate %zu bytes for the prepared map", mb);
        return CLI_BAD_INPUT;
    }
    if ((st = trn_map_build(&c->map, &c->cfg, &gg, mbuf, mb)) != TRN_OK) {
        snprintf(err, err_len, "--dem: cannot prepare the map: %s", trn_strerror(st));
        return CLI_BAD_INPUT;
    }
    return CLI_OK;
}

void cmd_localize_ctx_free(cmd_localize_ctx_t *c)
{
    free(c->mraw);
    c->mraw = NULL;
    dem_free(&c->g);
}

static void localize_report_text(const cmd_localize_ctx_t *c, const cmd_localize_params_t *p,
                                 const cmd_localize_out_t *o)
{
    const trn_map_cfg_t *cfg = &c->cfg;
    printf("estimate     x = %.3f m   y = %.3f m   status: %s\n", o->x_m, o->y_m,
           status_word(o->st));
    printf("prior        x = %.3f m   y = %.3f m   (window +-%g m = %ld cells)\n", p->prior[0],
           p->prior[1], p->window_m, o->radius);
    printf("covariance   sigma_x = %.4f m  sigma_y = %.4f m  rho = %.3f%s\n", o->res.sigma_x_m,
           o->res.sigma_y_m, o->rho_en, o->res.refined ? "   (height refinement)" : "   (eq. 6)");
    if (c->heading) {
        printf("heading      %+.3f deg   sigma %.3f deg   (searched %+.1f +- %.1f deg)\n",
               o->heading_deg, o->sigma_heading_deg, c->heading_deg, c->heading_win_deg);
    }
    printf("failure      probability %.3g%s\n", o->res.failure_probability,
           o->res.on_window_edge ? "   (best pose on the window edge: widen --window-m)" : "");
    printf("matched      %zu local %s, %llu poses scored exactly, %.1f ms\n", o->res.n_points,
           cfg->match == TRN_MATCH_HEIGHTS ? "heights" : "voxels",
           (unsigned long long)o->res.stats.poses_scored, o->time_ms);
    printf("map          match %s, bin %.4g m x %d, high-pass %.4g m, s %.4g m, local filter %s, "
           "refine %s\n",
           cfg->match == TRN_MATCH_HEIGHTS ? "heights" : "voxel", (double)cfg->terrain.zbin_m,
           (int)cfg->terrain.nz, (double)cfg->terrain.highpass_half_m, (double)cfg->sigma_m,
           cfg->local_highpass == TRN_LOCAL_HP_MAP ? "map" : "box", cfg->refine ? "on" : "off");
}

int trn_cmd_localize(int argc, char **argv)
{
    cmd_localize_params_t p;
    cmd_localize_ctx_t c;
    cmd_localize_out_t o;
    char err[CMD_ERR_LEN];
    int rc;

    cmd_localize_params_default(&p);
    rc = cmd_localize_parse(argc, argv, &p);
    if (rc != CLI_OK) {
        return rc == CLI_HELP ? 0 : rc;
    }
    rc = cmd_localize_prepare(&p, &c, err, sizeof err);
    if (rc != CLI_OK) {
        /* the map could not be prepared: one line, with --batch too */
        cli_fail("localize", "%s", err);
    } else if (p.batch_path != NULL) {
        rc = run_batch(&c, p.batch_path, p.window_m); /* prints its own reasons */
    } else {
        rc = cmd_localize_run(&c, p.local_path, p.prior, p.window_m, &o, err, sizeof err);
        if (rc == CLI_OK && p.json) {
            cmd_localize_report_json(stdout, &c, p.local_path, p.prior, p.window_m, &o, 0);
        } else if (rc == CLI_OK) {
            localize_report_text(&c, &p, &o);
        } else {
            cli_fail("localize", "%s", err);
        }
    }
    cmd_localize_ctx_free(&c);
    return rc;
}
