/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/cmd_field.c - `trn field`: the sensor uncertainty field (paper
 * section 6): for every rover position of an area, the predicted uncertainty
 * of its best landmark, computed coarse to fine by trn_field, as a GeoTIFF on
 * the DEM's grid.
 *
 * By default the ground path trn_field_fast (the same raster as trn_field,
 * bit for bit, about an order of magnitude faster, more memory: field.md);
 * --reference runs trn_field, the onboard algorithm.
 *
 * Progress: trn_field's progress callback (trn_field_cfg_t.progress) counts
 * the evaluations; the count is drawn on stderr only when stderr is a
 * terminal. The coarse lattice's size is known in advance, the refinement's
 * is not, so the line shows the coarse phase as a fraction and then the
 * running count. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "cmd_run.h"
#include "commands.h"
#include "dem_io.h"
#include "selmap.h"
#include "trn/trn.h"

/* ---- progress line (trn_field_cfg_t.progress) --------------------------- */
typedef struct {
    int active; /* stderr is a terminal */
    long count, shown;
    const cmd_field_result_t *r; /* its coarse_positions: the coarse lattice's size */
} field_prog_t;

static void prog_draw(field_prog_t *g)
{
    long coarse = g->r->coarse_positions;
    if (g->count <= coarse) {
        fprintf(stderr, "\rfield: coarse lattice %ld/%ld (%.0f%%)", g->count, coarse,
                100.0 * (double)g->count / (double)coarse);
    } else {
        fprintf(stderr, "\rfield: coarse lattice %ld/%ld, refining: %ld positions evaluated",
                coarse, coarse, g->count);
    }
    fflush(stderr);
    g->shown = g->count;
}

/* Called by the core after every evaluation (done = evaluations so far) and
 * once at the end (done = total); never cancels. */
static int32_t field_progress(void *user, uint32_t done, uint32_t total)
{
    field_prog_t *g = user;
    if (g->active && done < total) {
        g->count = (long)done;
        if (g->count - g->shown >= 16 || g->count == g->r->coarse_positions) {
            prog_draw(g);
        }
    }
    return 0;
}

/* "X0,Y0,X1,Y1" -> 4 finite numbers; 1 ok. */
static int parse_box(const char *s, double v[4])
{
    char buf[256], *p = buf, *c;
    int i;
    if (strlen(s) >= sizeof buf) {
        return 0;
    }
    memcpy(buf, s, strlen(s) + 1u);
    for (i = 0; i < 4; ++i) {
        c = strchr(p, ',');
        if ((c == NULL) != (i == 3)) {
            return 0;
        }
        if (c != NULL) {
            *c = '\0';
        }
        if (!cli_parse_double(p, &v[i])) {
            return 0;
        }
        p = c != NULL ? c + 1 : p;
    }
    return 1;
}

static int cmpf(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

static long lattice_count(long n, long step) { return (n - 1 + step - 1) / step + 1; }

void cmd_field_params_default(cmd_field_params_t *p)
{
    trn_field_cfg_t fcfg;
    memset(p, 0, sizeof *p);
    /* the defaults are the core's (trn_field_cfg_default), printed by --help from these */
    trn_field_cfg_default(&fcfg);
    p->coarse = fcfg.coarse_step_cells;
    p->margin = (double)fcfg.margin_rel;
    p->change = (double)fcfg.change_rel;
    selmap_opts_default(&p->so, 2);
}

int cmd_field_parse(int argc, char **argv, cmd_field_params_t *p)
{
    static const char *const k_not_field[] = {"--separation-m", NULL};
    int rc;
    cli_opt_t opts[7 + SELMAP_N_OPTS + 2];
    cli_cmd_t cmd = {
        "field",
        "Sensor uncertainty field: the predicted uncertainty of the best landmark from every "
        "rover\n"
        "position of an area (paper section 6), computed coarse to fine.",
        "Each evaluated position runs the selection of `trn select` (same options, heading fixed "
        "for\n"
        "the whole area); positions between evaluated ones are interpolated bilinearly (the "
        "number\n"
        "of evaluations is reported). Output: float32 GeoTIFF on the DEM's grid, metres; +inf "
        "where\n"
        "no target is informative, no-data (NaN) outside --area-m. --evaluated-out writes 1 where\n"
        "the value was computed, 0 where interpolated. Map configuration and the global map's "
        "error\n"
        "as `trn select` (default --map-config " SELMAP_MAP_CONFIG_DEFAULT ").",
        opts, 0};

    opts[0] = (cli_opt_t){
        "--dem", CLI_STRING, &p->dem_path, 0,
        0,       1,          "FILE",       "global DEM (any GDAL raster; map frame)",
        0};
    opts[1] = (cli_opt_t){
        "--out", CLI_STRING, &p->out, 0, 0, 1, "FILE.tif", "the field, GeoTIFF (metres)", 0};
    opts[2] = (cli_opt_t){"--area-m",
                          CLI_STRING,
                          &p->area_text,
                          0,
                          0,
                          0,
                          "X0,Y0,X1,Y1",
                          "rover positions covered: a map box in metres (default: the whole DEM)",
                          0};
    opts[3] = (cli_opt_t){"--coarse-step-cells",
                          CLI_LONG,
                          &p->coarse,
                          1,
                          256,
                          0,
                          "N",
                          "first lattice step, a power of two",
                          0};
    opts[4] = (cli_opt_t){"--margin-rel",
                          CLI_DOUBLE,
                          &p->margin,
                          0.0,
                          100.0,
                          0,
                          "M",
                          "refine squares within M x spread of the best",
                          0};
    opts[5] = (cli_opt_t){"--change-rel",
                          CLI_DOUBLE,
                          &p->change,
                          0.0,
                          100.0,
                          0,
                          "C",
                          "refine squares changing by more than C x spread",
                          0};
    opts[6] = (cli_opt_t){"--evaluated-out",
                          CLI_STRING,
                          &p->ev_out,
                          0,
                          0,
                          0,
                          "FILE.tif",
                          "also write 1 where computed, 0 where interpolated (default: none)",
                          0};
    selmap_opts(&p->so, opts + 7);
    cli_find(opts, 7 + SELMAP_N_OPTS, "--stride-cells")->help =
        "candidate lattice step, cells, as the core's select configuration";
    opts[7 + SELMAP_N_OPTS] = (cli_opt_t){
        "--json", CLI_FLAG, &p->json, 0, 0, 0, NULL, "print one JSON object instead of the summary",
        0};
    opts[7 + SELMAP_N_OPTS + 1] = (cli_opt_t){
        "--reference",
        CLI_FLAG,
        &p->reference,
        0,
        0,
        0,
        NULL,
        "run the onboard algorithm trn_field (same raster, slower, "
        "less memory) instead of trn_field_fast",
        0};
    /* the localizer's options (--match, --refine ...) and the ranking of distinct
     * next-best targets (--separation-m): the field keeps each position's best only */
    cmd.n_opts = cli_remove(opts, sizeof opts / sizeof opts[0],
                            mapopt_not_taken(MAPOPT_USE_PREDICT));
    cmd.n_opts = cli_remove(opts, cmd.n_opts, k_not_field);
    rc = cli_parse(&cmd, argc, argv);
    return rc != CLI_OK ? rc : selmap_check_use("field", &p->so);
}

/* The options that need no DEM; box: --area-m's numbers. */
static int field_check(const cmd_field_params_t *p, double box[4], char *err, size_t err_len)
{
    if ((p->coarse & (p->coarse - 1)) != 0) {
        snprintf(err, err_len, "--coarse-step-cells %ld is not a power of two", p->coarse);
        return CLI_BAD_INPUT;
    }
    if (p->area_text != NULL && !parse_box(p->area_text, box)) {
        snprintf(err, err_len, "--area-m: '%s' is not X0,Y0,X1,Y1 (four finite numbers)",
                 p->area_text);
        return CLI_BAD_INPUT;
    }
    if (p->area_text != NULL && (box[0] > box[2] || box[1] > box[3])) {
        snprintf(err, err_len, "--area-m: want X0 <= X1 and Y0 <= Y1, got %s", p->area_text);
        return CLI_BAD_INPUT;
    }
    return CLI_OK;
}

/* r->area, aw, ah: the whole DEM, or the cells whose centres lie in the box
 * (west/east -> columns, north/south -> rows). */
static int field_area(const cmd_field_params_t *p, const double box[4], cmd_field_result_t *r,
                      char *err, size_t err_len)
{
    const dem_t *d = &r->w.dem;
    double c0, c1, r0, r1;
    if (p->area_text == NULL) {
        r->area.x0 = 0;
        r->area.y0 = 0;
        r->area.x1 = d->width - 1;
        r->area.y1 = d->height - 1;
    } else {
        dem_map_to_cell(d->gt, box[0], box[3], &c0, &r0);
        dem_map_to_cell(d->gt, box[2], box[1], &c1, &r1);
        c0 = ceil(c0 - 1e-9);
        r0 = ceil(r0 - 1e-9);
        c1 = floor(c1 + 1e-9);
        r1 = floor(r1 + 1e-9);
        c0 = c0 < 0 ? 0 : c0;
        r0 = r0 < 0 ? 0 : r0;
        c1 = c1 > d->width - 1 ? d->width - 1 : c1;
        r1 = r1 > d->height - 1 ? d->height - 1 : r1;
        if (c0 > c1 || r0 > r1) {
            snprintf(err, err_len,
                     "--area-m %s holds no cell centre of the map (x %.3f..%.3f, y %.3f..%.3f)",
                     p->area_text, d->gt[0], d->gt[0] + d->width * d->cell_m,
                     d->gt[3] - d->height * d->cell_m, d->gt[3]);
            return CLI_BAD_INPUT;
        }
        r->area.x0 = (int32_t)c0;
        r->area.y0 = (int32_t)r0;
        r->area.x1 = (int32_t)c1;
        r->area.y1 = (int32_t)r1;
    }
    r->aw = (size_t)r->area.x1 - (size_t)r->area.x0 +
            1u; /* the area lies on the map: x0 <= x1, both >= 0 */
    r->ah = (size_t)r->area.y1 - (size_t)r->area.y0 + 1u;
    return CLI_OK;
}

/* The core over the area into fbuf (aw x ah) and ev; r->stats, wsb, secs. */
static int field_compute(const cmd_field_params_t *p, cmd_field_result_t *r, float *fbuf,
                         uint8_t *ev, char *err, size_t err_len)
{
    const selmap_t *w = &r->w;
    size_t n = r->aw * r->ah;
    trn_field_cfg_t fcfg;
    trn_grid_f32_t g;
    trn_status_t st;
    struct timespec t0, t1;
    void *wsraw = NULL, *ws;

    trn_field_cfg_default(&fcfg);
    fcfg.coarse_step_cells = (int32_t)p->coarse;
    fcfg.margin_rel = (float)p->margin;
    fcfg.change_rel = (float)p->change;
    fcfg.progress = p->progress;
    fcfg.progress_user = p->progress_user;
    r->wsb = p->reference ? trn_field_workspace_bytes(&w->scfg, &w->map, &w->k)
                          : trn_field_fast_workspace_bytes(&w->scfg, &w->map, &w->k, &w->pg);
    ws = r->wsb > 0 ? selmap_alloc16(r->wsb, &wsraw) : NULL;
    if (ws == NULL || fbuf == NULL || ev == NULL) {
        free(wsraw);
        snprintf(err, err_len, "cannot allocate %zu bytes of workspace and the %zu x %zu field",
                 r->wsb, r->aw, r->ah);
        return CLI_BAD_INPUT;
    }
    if (trn_grid_f32_init(&g, fbuf, n, (int32_t)r->aw, (int32_t)r->ah) != TRN_OK) {
        free(wsraw);
        snprintf(err, err_len, "area %zu x %zu rejected by the core", r->aw, r->ah);
        return CLI_BAD_INPUT;
    }
    r->coarse_positions = lattice_count((long)r->aw, p->coarse) *
                          lattice_count((long)r->ah, p->coarse);
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (p->reference) {
        st = trn_field(&w->map, &w->k, &w->pg, &w->scfg, &fcfg, w->heading_grid_rad, &r->area, &g,
                       ev, n, &r->stats, ws, r->wsb);
    } else {
        st = trn_field_fast(&w->map, &w->k, &w->pg, &w->scfg, &fcfg, w->heading_grid_rad, &r->area,
                            &g, ev, n, &r->stats, ws, r->wsb);
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    free(wsraw);
    r->secs = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    if (st != TRN_OK) {
        snprintf(err, err_len, "field failed: %s", trn_strerror(st));
        return CLI_BAD_INPUT;
    }
    if (r->stats.best_x < 0) {
        snprintf(
            err, err_len,
            "no informative target from any of the %u positions evaluated (featureless terrain?); "
            "nothing written",
            r->stats.evaluations);
        return CLI_NO_RESULT;
    }
    return CLI_OK;
}

/* The area's values (fbuf) or evaluated mask (ev, as 1 / 0) on the DEM's grid, NaN elsewhere, to path. */
static int field_write(const cmd_field_result_t *r, const char *path, const char *opt,
                       const float *fbuf, const uint8_t *ev, char *err, size_t err_len)
{
    const dem_t *d = &r->w.dem;
    char why[768];
    size_t nfull = (size_t)d->width * (size_t)d->height, i, x, y;
    float *full = malloc(nfull * sizeof *full);
    int rc = CLI_OK;
    if (full == NULL) {
        snprintf(err, err_len, "cannot allocate the %d x %d output", d->width, d->height);
        return CLI_BAD_INPUT;
    }
    for (i = 0; i < nfull; ++i) {
        full[i] = NAN;
    }
    for (y = 0; y < r->ah; ++y) {
        for (x = 0; x < r->aw; ++x) {
            size_t k = y * r->aw + x;
            full[((size_t)r->area.y0 + y) * (size_t)d->width + (size_t)r->area.x0 + x] =
                ev != NULL ? (ev[k] ? 1.0f : 0.0f) : fbuf[k];
        }
    }
    if (dem_write_gtiff(path, full, d->width, d->height, d->gt, d->srs_wkt, why, sizeof why) != 0) {
        snprintf(err, err_len, "%s: %s", opt, why);
        rc = CLI_BAD_INPUT;
    }
    free(full);
    return rc;
}

/* Summary: minimum (the core's), median of the finite values (fbuf reordered), infinite count. */
static void field_summary(cmd_field_result_t *r, float *fbuf)
{
    size_t n = r->aw * r->ah, nf = 0, i;
    r->vmed = NAN;
    r->n_inf = 0;
    for (i = 0; i < n; ++i) {
        if (isfinite(fbuf[i])) {
            fbuf[nf++] = fbuf[i];
        } else {
            ++r->n_inf;
        }
    }
    if (nf > 0) {
        qsort(fbuf, nf, sizeof *fbuf, cmpf);
        r->vmed = fbuf[nf / 2];
    }
    dem_cell_to_map(r->w.dem.gt, (double)r->stats.best_x, (double)r->stats.best_y, &r->bx, &r->by);
    r->vmin = r->stats.best_m;
}

/* The area (box: --area-m's numbers), the field and its files on the prepared r->w. */
static int field_run_on(const cmd_field_params_t *p, const double box[4], cmd_field_result_t *r,
                        char *err, size_t err_len)
{
    float *fbuf = NULL;
    uint8_t *ev = NULL;
    int rc;

    if ((rc = field_area(p, box, r, err, err_len)) != CLI_OK) {
        return rc;
    }
    fbuf = malloc(r->aw * r->ah * sizeof *fbuf);
    ev = malloc(r->aw * r->ah);
    rc = field_compute(p, r, fbuf, ev, err, err_len);
    if (rc == CLI_OK) {
        rc = field_write(r, p->out, "--out", fbuf, NULL, err, err_len);
    }
    if (rc == CLI_OK && p->ev_out != NULL) {
        rc = field_write(r, p->ev_out, "--evaluated-out", NULL, ev, err, err_len);
    }
    if (rc == CLI_OK) {
        field_summary(r, fbuf);
    }
    free(fbuf);
    free(ev);
    return rc;
}

/* r reset: no position yet; the options that need no DEM checked (box: --area-m's numbers). */
static int field_start(const cmd_field_params_t *p, double box[4], cmd_field_result_t *r, char *err,
                       size_t err_len)
{
    memset(r, 0, sizeof *r);
    r->bx = r->by = r->vmed = NAN;
    r->vmin = INFINITY;
    return field_check(p, box, err, err_len);
}

int cmd_field_run(const cmd_field_params_t *p, cmd_field_result_t *r, char *err, size_t err_len)
{
    double box[4];
    int rc = field_start(p, box, r, err, err_len);
    if (rc != CLI_OK) {
        return rc;
    }
    if (selmap_prepare(&r->w, p->dem_path, &p->so, err, err_len) != 0) {
        return CLI_BAD_INPUT;
    }
    return field_run_on(p, box, r, err, err_len);
}

int cmd_field_run_prepared(const cmd_field_params_t *p, const selmap_t *w, cmd_field_result_t *r,
                           char *err, size_t err_len)
{
    double box[4];
    int rc = field_start(p, box, r, err, err_len);
    r->w = *w;
    return rc != CLI_OK ? rc : field_run_on(p, box, r, err, err_len);
}

void cmd_field_result_free(cmd_field_result_t *r) { selmap_free(&r->w); }

void cmd_field_report_json(FILE *out, const cmd_field_params_t *p, const cmd_field_result_t *r)
{
    const dem_t *d = &r->w.dem;
    double ax0, ay0, ax1, ay1;
    json_t j;
    json_begin(&j, out);
    json_str(&j, "file", p->out);
    json_int(&j, "width", (long long)r->aw);
    json_int(&j, "height", (long long)r->ah);
    json_obj(&j, "area");
    dem_cell_to_map(d->gt, r->area.x0 - 0.5, r->area.y1 + 0.5, &ax0, &ay0);
    dem_cell_to_map(d->gt, r->area.x1 + 0.5, r->area.y0 - 0.5, &ax1, &ay1);
    json_num(&j, "x0_m", selmap_um(ax0));
    json_num(&j, "y0_m", selmap_um(ay0));
    json_num(&j, "x1_m", selmap_um(ax1));
    json_num(&j, "y1_m", selmap_um(ay1));
    json_obj_end(&j);
    json_int(&j, "cells", (long long)r->stats.cells);
    json_int(&j, "evaluations", (long long)r->stats.evaluations);
    json_obj(&j, "best");
    json_num(&j, "x_m", selmap_um(r->bx));
    json_num(&j, "y_m", selmap_um(r->by));
    json_num(&j, "uncertainty_m", r->vmin);
    json_obj_end(&j);
    json_num(&j, "median_uncertainty_m", r->vmed);
    json_int(&j, "no_target_cells", r->n_inf);
    json_num(&j, "heading_deg", p->so.heading_deg);
    json_int(&j, "coarse_step_cells", p->coarse);
    json_int(&j, "stride_cells", p->so.stride_cells);
    json_num(&j, "seconds", r->secs);
    /* trn_field_fast runs trn_field's path for the heading-searched prediction */
    json_str(&j, "algorithm",
             p->reference || (p->so.heading_search == 1 && p->so.heading_sigma_deg > 0.0)
                 ? "trn_field"
                 : "trn_field_fast");
    json_int(&j, "workspace_bytes", (long long)r->wsb);
    json_num(&j, "heading_sigma_deg", p->so.heading_sigma_deg);
    json_int(&j, "heading_search", p->so.heading_search);
    json_num(&j, "outlier_density_per_m", r->w.map.lnp.k_per_m);
    selmap_json_config(&j, &p->so, &r->w.cfg, r->w.sigma_h);
    json_end(&j);
}

static void field_report_text(const cmd_field_params_t *p, const cmd_field_result_t *r)
{
    const trn_field_stats_t *s = &r->stats;
    printf("wrote %s: field over %zu x %zu rover positions of %g m\n", p->out, r->aw, r->ah,
           r->w.dem.cell_m);
    printf("evaluated    %u of %u positions (%.1fx fewer), %.1f s\n", s->evaluations, s->cells,
           s->evaluations > 0 ? (double)s->cells / s->evaluations : 0.0, r->secs);
    if (s->best_x >= 0) {
        printf("best         x = %.3f m   y = %.3f m   uncertainty %.4f m\n", r->bx, r->by,
               r->vmin);
        printf("median       %.4f m; %ld positions with no informative target\n", r->vmed,
               r->n_inf);
    } else {
        printf("best         none: no position has an informative target\n");
    }
    selmap_print_config(&p->so, &r->w.cfg);
}

int trn_cmd_field(int argc, char **argv)
{
    cmd_field_params_t p;
    cmd_field_result_t r;
    field_prog_t prog = {0, 0, 0, NULL};
    char err[CMD_ERR_LEN];
    int rc;

    cmd_field_params_default(&p);
    rc = cmd_field_parse(argc, argv, &p);
    if (rc != CLI_OK) {
        return rc == CLI_HELP ? 0 : rc;
    }
    prog.active = isatty(2);
    prog.r = &r;
    p.progress = field_progress;
    p.progress_user = &prog;
    rc = cmd_field_run(&p, &r, err, sizeof err);
    if (prog.active && r.coarse_positions > 0) {
        prog_draw(&prog);
        fputc('\n', stderr);
    }
    if (rc != CLI_OK) {
        cli_fail("field", "%s", err);
    } else if (p.json) {
        cmd_field_report_json(stdout, &p, &r);
    } else {
        field_report_text(&p, &r);
    }
    cmd_field_result_free(&r);
    return rc;
}
