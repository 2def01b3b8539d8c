/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/cmd_select.c - `trn select`: the landmark a rover should sense
 * next (paper section 4): every candidate target's predicted localization
 * uncertainty from one rover position, the best one, the next best distinct
 * ones, and optionally the per-candidate uncertainty as a GeoTIFF (Fig. 2b).
 *
 * Frames as selmap.h: the rover and every reported position in map metres
 * (x east, y north), bearings in degrees counter-clockwise from the heading,
 * rho in the east-north frame (the core's column-row correlation with its
 * sign flipped). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cmd_run.h"
#include "commands.h"
#include "dem_io.h"
#include "selmap.h"
#include "trn/trn.h"

#define PI 3.14159265358979323846
#define EXIT_NO_TARGET CLI_NO_RESULT

static void target_json(json_t *j, const selmap_t *w, const trn_candidate_t *c)
{
    double x, y;
    dem_cell_to_map(w->dem.gt, (double)c->x, (double)c->y, &x, &y);
    json_num(j, "x_m", selmap_um(x));
    json_num(j, "y_m", selmap_um(y));
    json_num(j, "range_m", (double)c->range_m);
    json_num(j, "bearing_deg", -(double)c->bearing_rad * 180.0 / PI + 0.0);
    json_num(j, "sigma_x_m", c->sigma_x_m);
    json_num(j, "sigma_y_m", c->sigma_y_m);
    json_num(j, "rho", selmap_rho_en(c->rho));
    json_num(j, "uncertainty_m", c->uncertainty_m);
    json_num(j, "heading_m", c->heading_m);
}

void cmd_select_params_default(cmd_select_params_t *p)
{
    memset(p, 0, sizeof *p);
    p->next_best = 5;
    selmap_opts_default(&p->so, 1);
}

int cmd_select_parse(int argc, char **argv, cmd_select_params_t *p)
{
    cli_opt_t opts[4 + SELMAP_N_OPTS + 1];
    cli_cmd_t cmd = {
        "select",
        "Select the landmark to sense next: predicted localization uncertainty of every candidate\n"
        "target seen from the rover (paper section 4, eqs. 8-9, 6).",
        "Candidates are patch centres on a lattice of --stride-cells around the rover, within\n"
        "--min-range-m..--max-range-m and --pan-deg, patch inside the map. The global map's error\n"
        "grows with the distance to its sensing positions (eq. 8), the new local map's with the\n"
        "range from the rover (eq. 9). Output: the target (map x_m, y_m), its predicted sigma_x_m\n"
        "(east), sigma_y_m (north), rho (east-north), uncertainty_m = sqrt(sx^2 + sy^2), and the "
        "next\n"
        "best targets. --out-map: float32 GeoTIFF on the DEM's grid, each candidate's uncertainty "
        "(m)\n"
        "at its centre cell, +inf where its fit is ill-conditioned, no-data (NaN) elsewhere.\n"
        "Exit 3 (\"no informative target\") when no candidate is informative or none is in reach.\n"
        "The map configuration defaults to --map-config " SELMAP_MAP_CONFIG_DEFAULT
        "; the global map's\n"
        "error is eq. 8's S0 + K r^2 (--global-sigma-m, --global-sigma-k) or a per-cell raster\n"
        "(--global-error, the model where it has no data).",
        opts, 0};
    int rc;

    opts[0] = (cli_opt_t){
        "--dem", CLI_STRING, &p->dem_path, 0,
        0,       1,          "FILE",       "global DEM (any GDAL raster; map frame)",
        0};
    opts[1] = (cli_opt_t){
        "--rover", CLI_XY, p->rover_m, 0, 0, 1, "X,Y", "rover position, map metres", 0};
    opts[2] = (cli_opt_t){
        "--out-map",
        CLI_STRING,
        &p->out_map,
        0,
        0,
        0,
        "FILE.tif",
        "write every candidate's predicted uncertainty (m) as a GeoTIFF (default: none)",
        0};
    opts[3] = (cli_opt_t){"--next-best",
                          CLI_LONG,
                          &p->next_best,
                          0,
                          64,
                          0,
                          "N",
                          "distinct next best targets listed",
                          0};
    selmap_opts(&p->so, opts + 4);
    cli_find(opts, 4 + SELMAP_N_OPTS, "--stride-cells")->help =
        "candidate lattice step, cells (1: every cell, the full Fig. 2b map)";
    opts[4 + SELMAP_N_OPTS] = (cli_opt_t){
        "--json", CLI_FLAG, &p->json, 0, 0, 0, NULL, "print one JSON object instead of the summary",
        0};
    /* the localizer's options (--match, --refine ...): no selection reads them */
    cmd.n_opts = cli_remove(opts, sizeof opts / sizeof opts[0],
                            mapopt_not_taken(MAPOPT_USE_PREDICT));
    rc = cli_parse(&cmd, argc, argv);
    return rc != CLI_OK ? rc : selmap_check_use("select", &p->so);
}

/* --out-map: each candidate's uncertainty at its centre cell, +inf where ill-conditioned, NaN elsewhere. */
static int write_out_map(const cmd_select_params_t *p, const cmd_select_result_t *r, char *err,
                         size_t err_len)
{
    char why[768];
    const dem_t *d = &r->w.dem;
    size_t n = (size_t)d->width * (size_t)d->height, i;
    float *map = malloc(n * sizeof *map);
    int rc = 0;
    if (map == NULL) {
        snprintf(err, err_len, "cannot allocate the output map");
        return CLI_BAD_INPUT;
    }
    for (i = 0; i < n; ++i) {
        map[i] = NAN;
    }
    for (i = 0; i < r->res.n_candidates; ++i) {
        const trn_candidate_t *c = &r->cands[i];
        map[(size_t)c->y * (size_t)d->width + (size_t)c->x] = c->informative
                                                                  ? (float)c->uncertainty_m
                                                                  : (float)INFINITY;
    }
    if (dem_write_gtiff(p->out_map, map, d->width, d->height, d->gt, d->srs_wkt, why, sizeof why) !=
        0) {
        snprintf(err, err_len, "--out-map: %s", why);
        rc = CLI_BAD_INPUT;
    }
    free(map);
    return rc;
}

/* The selection from the rover's sub-cell position on the prepared DEM r->w. */
static int select_on_map(const cmd_select_params_t *p, cmd_select_result_t *r, char *err,
                         size_t err_len)
{
    const selmap_t *w = &r->w;
    const selmap_opts_t *so = &p->so;
    double rc_f, rr_f;
    size_t cap, wsb, nrank;
    trn_rover_t rover;
    trn_status_t st;
    void *wsraw = NULL, *ws;

    dem_map_to_cell(w->dem.gt, p->rover_m[0], p->rover_m[1], &rc_f, &rr_f);
    rover.pos.x_cells = (float)rc_f;
    rover.pos.y_cells = (float)rr_f;
    rover.heading_rad = w->heading_grid_rad;
    cap = trn_select_max_candidates(&w->scfg, (float)w->dem.cell_m);
    wsb = trn_select_workspace_bytes(&w->scfg, &w->map, &w->k);
    nrank = (size_t)p->next_best + 1u;
    r->cands = cap > 0 ? malloc(cap * sizeof *r->cands) : NULL;
    r->ranked = malloc(nrank * sizeof *r->ranked);
    ws = wsb > 0 ? selmap_alloc16(wsb, &wsraw) : NULL;
    if (r->cands == NULL || r->ranked == NULL || ws == NULL) {
        free(wsraw);
        snprintf(err, err_len, "cannot allocate %zu candidates and %zu bytes of workspace", cap,
                 wsb);
        return CLI_BAD_INPUT;
    }
    st = trn_select(&w->map, &w->k, &w->pg, &w->scfg, &rover, r->cands, cap, r->ranked, nrank,
                    &r->res, ws, wsb);
    free(wsraw);
    if (st == TRN_E_NOTARGET) {
        if (r->res.n_candidates == 0) {
            snprintf(
                err, err_len,
                "no informative target: no candidate lies within reach (range %g..%g m, pan %g..%g "
                "deg, patch inside the map)",
                so->min_range_m, so->max_range_m, so->pan_deg[0], so->pan_deg[1]);
        } else {
            snprintf(
                err, err_len,
                "no informative target: all %zu candidates are featureless (their predicted fit is "
                "ill-conditioned)",
                r->res.n_candidates);
        }
        return EXIT_NO_TARGET;
    }
    if (st != TRN_OK) {
        snprintf(err, err_len, "selection failed: %s", trn_strerror(st));
        return CLI_BAD_INPUT;
    }
    return CLI_OK;
}

/* The rover's position, the selection and --out-map on the prepared r->w. */
static int select_run_on(const cmd_select_params_t *p, cmd_select_result_t *r, char *err,
                         size_t err_len)
{
    const dem_t *d = &r->w.dem;
    int rcol, rrow, rc;

    if (!dem_cell_of(d, p->rover_m[0], p->rover_m[1], &rcol, &rrow)) {
        snprintf(err, err_len, "--rover %.3f,%.3f is off the map (x %.3f..%.3f, y %.3f..%.3f)",
                 p->rover_m[0], p->rover_m[1], d->gt[0], d->gt[0] + d->width * d->cell_m,
                 d->gt[3] - d->height * d->cell_m, d->gt[3]);
        return CLI_BAD_INPUT;
    }
    rc = select_on_map(p, r, err, err_len);
    if (rc == CLI_OK && p->out_map != NULL) {
        rc = write_out_map(p, r, err, err_len);
    }
    return rc;
}

int cmd_select_run(const cmd_select_params_t *p, cmd_select_result_t *r, char *err, size_t err_len)
{
    memset(r, 0, sizeof *r);
    if (selmap_prepare(&r->w, p->dem_path, &p->so, err, err_len) != 0) {
        return CLI_BAD_INPUT;
    }
    return select_run_on(p, r, err, err_len);
}

int cmd_select_run_prepared(const cmd_select_params_t *p, const selmap_t *w, cmd_select_result_t *r,
                            char *err, size_t err_len)
{
    memset(r, 0, sizeof *r);
    r->w = *w;
    return select_run_on(p, r, err, err_len);
}

void cmd_select_result_release(cmd_select_result_t *r)
{
    free(r->cands);
    free(r->ranked);
    r->cands = NULL;
    r->ranked = NULL;
}

void cmd_select_result_free(cmd_select_result_t *r)
{
    cmd_select_result_release(r);
    selmap_free(&r->w);
}

void cmd_select_report_json(FILE *out, const cmd_select_params_t *p, const cmd_select_result_t *r)
{
    const trn_candidate_t *b = &r->cands[r->res.best];
    const selmap_t *w = &r->w;
    double tx, ty;
    size_t i;
    json_t j;
    json_begin(&j, out);
    dem_cell_to_map(w->dem.gt, (double)b->x, (double)b->y, &tx, &ty);
    json_obj(&j, "target");
    json_num(&j, "x_m", selmap_um(tx));
    json_num(&j, "y_m", selmap_um(ty));
    json_num(&j, "range_m", (double)b->range_m);
    json_num(&j, "bearing_deg", -(double)b->bearing_rad * 180.0 / PI + 0.0);
    json_obj_end(&j);
    json_num(&j, "sigma_x_m", b->sigma_x_m);
    json_num(&j, "sigma_y_m", b->sigma_y_m);
    json_num(&j, "rho", selmap_rho_en(b->rho));
    json_num(&j, "uncertainty_m", b->uncertainty_m);
    json_num(&j, "heading_m", b->heading_m);
    json_obj(&j, "rover");
    json_num(&j, "x_m", p->rover_m[0]);
    json_num(&j, "y_m", p->rover_m[1]);
    json_num(&j, "heading_deg", p->so.heading_deg);
    json_obj_end(&j);
    json_arr(&j, "next_best");
    for (i = 1; i < r->res.n_ranked; ++i) {
        json_obj(&j, NULL);
        target_json(&j, w, &r->cands[r->ranked[i]]);
        json_obj_end(&j);
    }
    json_arr_end(&j);
    json_int(&j, "candidates", (long long)r->res.n_candidates);
    json_int(&j, "informative", (long long)r->res.n_informative);
    json_num(&j, "min_range_m", p->so.min_range_m);
    json_num(&j, "max_range_m", p->so.max_range_m);
    json_int(&j, "stride_cells", p->so.stride_cells);
    json_int(&j, "patch_cells", (long long)r->res.patch_cells);
    json_num(&j, "patch_m", r->res.patch_cells * w->dem.cell_m);
    json_num(&j, "cell_m", w->dem.cell_m);
    json_arr(&j, "sensors");
    for (i = 0; i < w->n_sensors; ++i) {
        json_obj(&j, NULL);
        json_num(&j, "x_m", selmap_um(w->sensors_m[i][0]));
        json_num(&j, "y_m", selmap_um(w->sensors_m[i][1]));
        json_obj_end(&j);
    }
    json_arr_end(&j);
    if (p->out_map != NULL) {
        json_str(&j, "out_map", p->out_map);
    }
    json_num(&j, "heading_sigma_deg", p->so.heading_sigma_deg);
    json_int(&j, "heading_search", p->so.heading_search);
    selmap_json_config(&j, &p->so, &w->cfg, w->sigma_h);
    json_end(&j);
}

static void select_report_text(const cmd_select_params_t *p, const cmd_select_result_t *r)
{
    const trn_candidate_t *b = &r->cands[r->res.best];
    const selmap_t *w = &r->w;
    double x, y;
    size_t i;
    dem_cell_to_map(w->dem.gt, (double)b->x, (double)b->y, &x, &y);
    printf("rover        x = %.3f m   y = %.3f m   heading %g deg\n", p->rover_m[0], p->rover_m[1],
           p->so.heading_deg);
    printf("target       x = %.3f m   y = %.3f m   range %.2f m   bearing %.0f deg\n", x, y,
           (double)b->range_m, -(double)b->bearing_rad * 180.0 / PI + 0.0);
    printf("predicted    sigma_x = %.4f m  sigma_y = %.4f m  rho = %.3f   uncertainty %.4f m\n",
           b->sigma_x_m, b->sigma_y_m, selmap_rho_en(b->rho), b->uncertainty_m);
    for (i = 1; i < r->res.n_ranked; ++i) {
        const trn_candidate_t *c = &r->cands[r->ranked[i]];
        dem_cell_to_map(w->dem.gt, (double)c->x, (double)c->y, &x, &y);
        printf("next best %zu  x = %.3f m   y = %.3f m   range %.2f m   uncertainty %.4f m\n", i, x,
               y, (double)c->range_m, c->uncertainty_m);
    }
    printf("candidates   %zu, %zu informative, patch %d x %d cells (%.2f m)\n", r->res.n_candidates,
           r->res.n_informative, r->res.patch_cells, r->res.patch_cells,
           r->res.patch_cells * w->dem.cell_m);
    selmap_print_config(&p->so, &w->cfg);
    if (p->out_map != NULL) {
        printf("wrote %s\n", p->out_map);
    }
}

int trn_cmd_select(int argc, char **argv)
{
    cmd_select_params_t p;
    cmd_select_result_t r;
    char err[CMD_ERR_LEN];
    int rc;

    cmd_select_params_default(&p);
    rc = cmd_select_parse(argc, argv, &p);
    if (rc != CLI_OK) {
        return rc == CLI_HELP ? 0 : rc;
    }
    rc = cmd_select_run(&p, &r, err, sizeof err);
    if (rc != CLI_OK) {
        cli_fail("select", "%s", err);
    } else if (p.json) {
        cmd_select_report_json(stdout, &p, &r);
    } else {
        select_report_text(&p, &r);
    }
    cmd_select_result_free(&r);
    return rc;
}
