/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/selmap.c - see selmap.h. */
#include "selmap.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

void *selmap_alloc16(size_t n, void **raw)
{
    uint8_t *p = malloc(n + 16u);
    *raw = p;
    if (p == NULL) {
        return NULL;
    }
    return p + ((16u - ((uintptr_t)p & 15u)) & 15u);
}

double selmap_um(double v_m) { return isfinite(v_m) ? floor(v_m * 1e6 + 0.5) / 1e6 : v_m; }

double selmap_rho_en(double rho_grid)
{
    if (!isfinite(rho_grid)) {
        return rho_grid;
    }
    return rho_grid == 0.0 ? 0.0 : -rho_grid;
}

void selmap_opts_default(selmap_opts_t *o, long stride_cells)
{
    trn_select_cfg_t c;
    trn_select_cfg_default(&c);
    memset(o, 0, sizeof *o);
    o->band = 1;
    o->heading_deg = 0.0;
    o->pan_deg[0] = -180.0;
    o->pan_deg[1] = 180.0;
    o->min_range_m = c.min_range_m;
    o->max_range_m = c.max_range_m;
    o->footprint_m = c.footprint_radius_m;
    o->patch_m = c.patch_m;
    o->separation_m = c.min_separation_m;
    o->stride_cells = stride_cells;
    o->sensors = NULL;
    mapopt_init(&o->mo);
    o->mo.config = SELMAP_MAP_CONFIG_DEFAULT;
    o->gsig_m = -1.0;
    o->gsig_k = -1.0;
    o->gerr = NULL;
    o->points_per_cell = 0.0;
}

void selmap_gerr_opts(selmap_opts_t *o, cli_opt_t *d)
{
    /* the model's default is the core's (trn_sigma_global_default), printed from it */
    static char h_m[192], h_k[128];
    trn_sigma_model_t gm;
    trn_sigma_global_default(&gm);
    snprintf(h_m, sizeof h_m,
             "global map's error at its sensing position, m (eq. 8: S0 + K r^2; the height "
             "prediction: the DEM's height error, one sd; default %g)",
             (double)gm.sigma_min_m);
    snprintf(h_k, sizeof h_k,
             "global map's error growth with squared range from the nearest sensing position, 1/m "
             "(default %g)",
             (double)gm.k_per_m);
    const cli_opt_t t[SELMAP_N_GERR_OPTS] = {
        {"--global-sigma-m", CLI_DOUBLE, &o->gsig_m, 0.0, 1e5, 0, "S0", h_m, 0},
        {"--global-sigma-k", CLI_DOUBLE, &o->gsig_k, 0.0, 100.0, 0, "K", h_k, 0},
        {"--global-error", CLI_STRING, &o->gerr, 0, 0, 0, "FILE",
         "per-cell error raster of the global map, m (e.g. a HiRISE DTM's), the --dem's grid; "
         "no-data = the model (default: none)",
         0},
    };
    memcpy(d, t, sizeof t);
}

void selmap_gerr_model(const selmap_opts_t *o, trn_sigma_model_t *m)
{
    trn_sigma_global_default(m);
    if (o->gsig_m >= 0.0) {
        m->sigma_min_m = (float)o->gsig_m;
    }
    if (o->gsig_k >= 0.0) {
        m->k_per_m = (float)o->gsig_k;
    }
}

int selmap_read_error(const char *path, const dem_t *dem, dem_t *e, char *err, size_t err_len)
{
    char why[640];
    size_t i;
    if (dem_read(path, 1, TRN_MAX_DIM, e, why, sizeof why) != 0) {
        snprintf(err, err_len, "--global-error: %s", why);
        return -1;
    }
    if (e->width != dem->width || e->height != dem->height) {
        snprintf(err, err_len,
                 "--global-error is %d x %d cells, --dem %d x %d: the error raster must be on the "
                 "DEM's grid",
                 e->width, e->height, dem->width, dem->height);
        goto fail;
    }
    for (i = 0; i < 6; ++i) {
        if (fabs(e->gt[i] - dem->gt[i]) > 1e-6 * dem->cell_m) {
            snprintf(err, err_len,
                     "--global-error's geotransform differs from --dem's (origin %.3f,%.3f cell %g "
                     "m against "
                     "%.3f,%.3f cell %g m): the error raster must be on the DEM's grid",
                     e->gt[0], e->gt[3], e->cell_m, dem->gt[0], dem->gt[3], dem->cell_m);
            goto fail;
        }
    }
    for (i = 0; i < (size_t)e->width * (size_t)e->height; ++i) {
        if (!isnan(e->data[i]) && !(e->data[i] >= 0.0f && e->data[i] <= 1e6f)) {
            snprintf(err, err_len,
                     "--global-error: cell (column %zu, row %zu) is %g m; errors must be 0..1e6 m "
                     "or no-data",
                     i % (size_t)e->width, i / (size_t)e->width, (double)e->data[i]);
            goto fail;
        }
    }
    return 0;
fail:
    dem_free(e);
    return -1;
}

int selmap_prob_global(const selmap_opts_t *o, const dem_t *dem, const trn_kernels_t *k,
                       const trn_xy_t *sensors, size_t n_sensors, const trn_map_t *map,
                       trn_vol_f32_t *pg, void **pgraw, char *err, size_t err_len)
{
    size_t nvox = (size_t)dem->width * (size_t)dem->height * (size_t)map->dist.nz, wb;
    void *wraw = NULL, *ws;
    trn_sigma_model_t gm;
    trn_status_t st;
    dem_t e;
    int rc = -1;
    memset(&e, 0, sizeof e);
    selmap_gerr_model(o, &gm);
    *pgraw = NULL;
    if (o->gerr != NULL && selmap_read_error(o->gerr, dem, &e, err, err_len) != 0) {
        return -1;
    }
    pg->data = selmap_alloc16(nvox * sizeof(float), pgraw);
    wb = trn_prob_global_workspace_bytes(dem->width, dem->height);
    ws = wb > 0 ? selmap_alloc16(wb, &wraw) : NULL;
    if (pg->data == NULL || ws == NULL) {
        snprintf(err, err_len, "cannot allocate %zu bytes for the probability map",
                 nvox * sizeof(float) + wb);
        goto done;
    }
    pg->nx = dem->width;
    pg->ny = dem->height;
    pg->nz = map->dist.nz;
    if (o->gerr != NULL) {
        trn_grid_f32_t g;
        st = trn_grid_f32_init(&g, e.data, (size_t)e.width * (size_t)e.height, e.width, e.height);
        if (st == TRN_OK) {
            st = trn_prob_global_raster(k, &gm, sensors, n_sensors, &g, map, pg, ws, wb);
        }
    } else {
        st = trn_prob_global_map(k, &gm, sensors, n_sensors, map, pg, ws, wb);
    }
    if (st != TRN_OK) {
        snprintf(err, err_len, "probability map (eq. 8): %s", trn_strerror(st));
        goto done;
    }
    rc = 0;
done:
    free(wraw);
    dem_free(&e);
    if (rc != 0) {
        free(*pgraw);
        *pgraw = NULL;
        pg->data = NULL;
    }
    return rc;
}

void selmap_json_config(json_t *j, const selmap_opts_t *o, const trn_map_cfg_t *cfg, double sigma_h)
{
    trn_sigma_model_t gm;
    selmap_gerr_model(o, &gm);
    json_obj(j, "global_error");
    json_num(j, "sigma_m", gm.sigma_min_m);
    json_num(j, "k_per_m", gm.k_per_m);
    if (o->gerr != NULL) {
        json_str(j, "raster", o->gerr);
    } else {
        json_num(j, "raster", NAN); /* null */
    }
    json_obj_end(j);
    json_str(j, "map_config_name", o->mo.config);
    json_str(j, "predicts", cfg->match == (int32_t)TRN_MATCH_HEIGHTS ? "heights" : "voxel");
    json_num(j, "points_per_cell", o->points_per_cell);
    json_num(j, "sigma_h_m", sigma_h);
    mapopt_json(j, cfg);
}

void selmap_opts(selmap_opts_t *o, cli_opt_t *d)
{
    const cli_opt_t t[SELMAP_N_SEL_OPTS] = {
        {"--band", CLI_LONG, &o->band, 1, 65535, 0, "N", "band of --dem", 0},
        {"--heading-deg", CLI_DOUBLE, &o->heading_deg, -360.0, 360.0, 0, "A",
         "rover heading, degrees counter-clockwise from east", 0},
        {"--heading-sigma-deg", CLI_DOUBLE, &o->heading_sigma_deg, 0.0,
         (double)TRN_SELECT_MAX_SIGMA_HEADING_RAD * 180.0 / PI, 0, "D",
         "the heading's uncertainty (1 sigma), degrees: each target's predicted covariance adds (D "
         "r)^2 across its line "
         "of sight, so nearer targets win as it grows (docs/method.md 4)",
         0},
        {"--heading-search", CLI_LONG, &o->heading_search, 0, 1, 0, "0|1",
         "1: the target will be matched with the heading searched too (localize "
         "--heading-window-deg): with --heading-sigma-deg D each prediction is the position's "
         "marginal of the (x, y, heading) fit with that prior, so patches whose structure spreads "
         "across them pin the heading and lose less (docs/method.md 4) (default 0: matched in x "
         "and y, the lever arm)",
         0},
        {"--pan-deg", CLI_XY, o->pan_deg, 0, 0, 0, "MIN,MAX",
         "bearings the mast can look at, degrees from the heading, CCW positive", 0},
        {"--min-range-m", CLI_DOUBLE, &o->min_range_m, 0.0, 1e6, 0, "R", "nearest target, m", 0},
        {"--max-range-m", CLI_DOUBLE, &o->max_range_m, 1e-3, 1e6, 0, "R", "farthest target, m", 0},
        {"--footprint-m", CLI_DOUBLE, &o->footprint_m, 0.0, 1e5, 0, "R",
         "rover footprint radius no patch may touch, m", 0},
        {"--patch-m", CLI_DOUBLE, &o->patch_m, 1e-3, 1e6, 0, "S",
         "side of the sensed patch, m (at least 3 cells)", 0},
        {"--stride-cells", CLI_LONG, &o->stride_cells, 1, 64, 0, "N", NULL, 0},
        {"--separation-m", CLI_DOUBLE, &o->separation_m, 0.0, 1e6, 0, "D",
         "least distance between ranked targets, m", 0},
        {"--sensors", CLI_STRING, &o->sensors, 0, 0, 0, "X,Y[;X,Y..]",
         "where the global map was sensed from, map m, up to 64 (default: the DEM's centre)", 0},
        {"--points-per-cell", CLI_DOUBLE, &o->points_per_cell, 0.0, TRN_POINT_COUNT_MAX, 0, "N",
         "the height prediction for a rover that bins its stereo points and passes their counts "
         "(localize --count-band): the points it expects in each seen cell, each cell then the "
         "mean of N, with its points' centroid's jitter (docs/method.md 4) (default 0: one "
         "measurement a cell; else at least 1)",
         0},
        {"--outlier-density", CLI_DOUBLE, &o->outlier_k, 1e-30, 1e30, 0, "K",
         "the map's outlier density K of ln p, 1/m (default: from the DEM; a tile of a larger map "
         "takes the whole map's, the JSON's outlier_density_per_m)",
         0},
    };
    size_t i;
    memcpy(d, t, sizeof t);
    selmap_gerr_opts(o, d + SELMAP_N_SEL_OPTS);
    mapopt_cli(&o->mo, d + SELMAP_N_SEL_OPTS + SELMAP_N_GERR_OPTS);
    for (i = SELMAP_N_SEL_OPTS + SELMAP_N_GERR_OPTS; i < SELMAP_N_OPTS; ++i) {
        if (strcmp(d[i].name, "--map-config") == 0) {
            d[i].help = "map configuration (default " SELMAP_MAP_CONFIG_DEFAULT
                        ", as `trn localize`): auto (from the DEM, docs/method.md 9), the height "
                        "matcher's prediction; or paper (as in the paper, scaled to the cell), the "
                        "voxel prediction (eqs. 8-9)";
        }
    }
}

int selmap_check_use(const char *cmd, const selmap_opts_t *o)
{
    char err[512];
    const char *voxel_only;
    if (mapopt_check_use(&o->mo, MAPOPT_USE_PREDICT, err, sizeof err) != 0) {
        fprintf(cli_message_stream(), "trn %s: %s\n", cmd, err);
        return CLI_USAGE;
    }
    /* P_G (eq. 8) is the voxel prediction's: the height prediction reads the
     * DEM's error as one sd (--global-sigma-m) */
    voxel_only = o->sensors != NULL        ? "--sensors"
                 : o->gsig_k >= 0.0        ? "--global-sigma-k"
                 : o->gerr != NULL         ? "--global-error"
                 : o->outlier_k > 0.0      ? "--outlier-density"
                 : o->mo.inlier_prob > 0.0 ? "--inlier-prob"
                                           : NULL;
    if (mapopt_heights(&o->mo) && voxel_only != NULL) {
        fprintf(cli_message_stream(),
                "trn %s: %s applies to the voxel prediction (--match voxel, or --map-config "
                "paper); the height prediction reads the DEM's heights and its error as one sd, "
                "--global-sigma-m\n",
                cmd, voxel_only);
        return CLI_USAGE;
    }
    if (o->points_per_cell > 0.0 && o->points_per_cell < 1.0) {
        fprintf(cli_message_stream(),
                "trn %s: --points-per-cell %g: a binned cell holds at least one point (0: one "
                "measurement a cell)\n",
                cmd, o->points_per_cell);
        return CLI_USAGE;
    }
    if (o->points_per_cell > 0.0 && !mapopt_heights(&o->mo)) {
        fprintf(cli_message_stream(),
                "trn %s: --points-per-cell applies to the height prediction; the voxel "
                "prediction (--match voxel, or --map-config paper) models a probability map, not "
                "binned heights\n",
                cmd);
        return CLI_USAGE;
    }
    if (o->heading_search == 1 && !(o->heading_sigma_deg > 0.0)) {
        fprintf(cli_message_stream(),
                "trn %s: --heading-search 1 needs --heading-sigma-deg above 0 (with the heading "
                "known there is no heading to search)\n",
                cmd);
        return CLI_USAGE;
    }
    return CLI_OK;
}

void selmap_free(selmap_t *w)
{
    free(w->mraw);
    free(w->pgraw);
    dem_free(&w->dem);
    w->mraw = w->pgraw = NULL;
}

/* "X,Y;X,Y;..." -> map metres; 1 ok, 0 with a reason in err. */
static int parse_sensors(const char *text, double out[][2], size_t cap, size_t *n, char *err,
                         size_t err_len)
{
    char buf[4096], *tok, *next;
    size_t len = strlen(text);
    *n = 0;
    if (len == 0 || len >= sizeof buf) {
        snprintf(err, err_len, "--sensors: expected X,Y[;X,Y...], got '%s'", text);
        return 0;
    }
    memcpy(buf, text, len + 1);
    for (tok = buf; tok != NULL; tok = next) {
        next = strchr(tok, ';');
        if (next != NULL) {
            *next++ = '\0';
        }
        if (*n >= cap) {
            snprintf(err, err_len, "--sensors: more than %zu positions", cap);
            return 0;
        }
        if (!cli_parse_xy(tok, &out[*n][0], &out[*n][1])) {
            snprintf(err, err_len, "--sensors: '%s' is not a pair X,Y of finite numbers", tok);
            return 0;
        }
        ++*n;
    }
    if (*n == 0) {
        snprintf(err, err_len, "--sensors: expected X,Y[;X,Y...], got '%s'", text);
        return 0;
    }
    return 1;
}

/* Options that need no DEM: cheap mistakes fail fast. */
static int check_opts(selmap_t *w, const selmap_opts_t *o, char *err, size_t err_len)
{
    if (o->pan_deg[0] < -180.0 || o->pan_deg[1] > 180.0 || o->pan_deg[0] > o->pan_deg[1]) {
        snprintf(err, err_len, "--pan-deg %g,%g: want -180 <= MIN <= MAX <= 180", o->pan_deg[0],
                 o->pan_deg[1]);
        return -1;
    }
    if (o->min_range_m > o->max_range_m) {
        snprintf(err, err_len, "--min-range-m %g is above --max-range-m %g", o->min_range_m,
                 o->max_range_m);
        return -1;
    }
    if (o->sensors != NULL && !parse_sensors(o->sensors, w->sensors_m, TRN_SPREAD_MAX_SENSORS,
                                             &w->n_sensors, err, err_len)) {
        return -1;
    }
    return 0;
}

/* Selection rules in the grid frame. */
static int select_rules(selmap_t *w, const selmap_opts_t *o, double cell, char *err, size_t err_len)
{
    trn_select_cfg_t *c = &w->scfg;
    trn_status_t st;

    trn_select_cfg_default(c);
    c->min_range_m = (float)o->min_range_m;
    c->max_range_m = (float)o->max_range_m;
    c->pan_min_rad = (float)(-o->pan_deg[1] * PI / 180.0);
    c->pan_max_rad = (float)(-o->pan_deg[0] * PI / 180.0);
    c->footprint_radius_m = (float)o->footprint_m;
    c->patch_m = (float)o->patch_m;
    c->stride_cells = (int32_t)o->stride_cells;
    c->min_separation_m = (float)o->separation_m;
    c->sigma_heading_rad = (float)(o->heading_sigma_deg * PI / 180.0);
    c->heading_search = (int32_t)o->heading_search;
    if (o->gsig_m >= 0.0) { /* the height prediction's DEM error (select.h) */
        c->map_sigma_m = (float)o->gsig_m;
    }
    c->points_per_cell = (float)o->points_per_cell;
    if ((st = trn_select_cfg_check(c, (float)cell)) != TRN_OK) {
        if (o->patch_m / cell < 2.5) {
            snprintf(err, err_len,
                     "--patch-m %g is %.1f cells of %g m; at least 3 cells are needed", o->patch_m,
                     o->patch_m / cell, cell);
        } else {
            snprintf(err, err_len,
                     "selection rules rejected for %g m cells (range up to %g m = %.0f cells, at "
                     "most %d): %s",
                     cell, o->max_range_m, o->max_range_m / cell, TRN_MAX_DIM, trn_strerror(st));
        }
        return -1;
    }
    w->heading_grid_rad = (float)(-o->heading_deg * PI / 180.0);
    return 0;
}

/* The map (configuration from o->mo; default SELMAP_MAP_CONFIG_DEFAULT) and the kernels. */
static int build_map(selmap_t *w, const selmap_opts_t *o, char *err, size_t err_len)
{
    char why[768];
    size_t mb;
    trn_grid_f32_t gg;
    trn_status_t st;
    void *mbuf;

    if (mapopt_config(&o->mo, w->dem.data, w->dem.width, w->dem.height, w->dem.cell_m, &w->cfg,
                      &w->sigma_h, why, sizeof why) != 0) {
        snprintf(err, err_len, "--dem: %s", why);
        return -1;
    }
    if (trn_grid_f32_init(&gg, w->dem.data, (size_t)w->dem.width * (size_t)w->dem.height,
                          w->dem.width, w->dem.height) != TRN_OK) {
        snprintf(err, err_len, "DEM size %d x %d rejected by the core", w->dem.width,
                 w->dem.height);
        return -1;
    }
    mb = trn_map_bytes(&w->cfg, w->dem.width, w->dem.height);
    mbuf = mb > 0 ? selmap_alloc16(mb, &w->mraw) : NULL;
    if (mbuf == NULL) {
        snprintf(err, err_len, "cannot allocate %zu bytes for the prepared map", mb);
        return -1;
    }
    if ((st = trn_map_build(&w->map, &w->cfg, &gg, mbuf, mb)) != TRN_OK) {
        snprintf(err, err_len, "--dem: cannot prepare the map: %s", trn_strerror(st));
        return -1;
    }
    if (o->outlier_k > 0.0) { /* a tile of a larger map: that map's K, not the tile's */
        trn_lik_cfg_t lik;
        lik.cell_m = w->cfg.terrain.cell_m;
        lik.sigma_m = w->cfg.sigma_m;
        lik.inlier_prob = w->cfg.inlier_prob;
        lik.cap = w->cfg.cap;
        if ((st = trn_lnp_table_build(&w->map.lnp, &lik, o->outlier_k)) != TRN_OK) {
            snprintf(err, err_len, "--outlier-density %g: %s", o->outlier_k, trn_strerror(st));
            return -1;
        }
    }
    if ((st = trn_kernels_build(&w->k, TRN_KERNEL_SIGMA0_DEFAULT_CELLS)) != TRN_OK) {
        snprintf(err, err_len, "kernels: %s", trn_strerror(st));
        return -1;
    }
    return 0;
}

/* Sensing positions of the global map in cells: given, or the DEM's centre. */
static int sensor_cells(selmap_t *w, char *err, size_t err_len)
{
    double col, row;
    size_t i;

    if (w->n_sensors == 0) {
        dem_cell_to_map(w->dem.gt, 0.5 * (w->dem.width - 1), 0.5 * (w->dem.height - 1),
                        &w->sensors_m[0][0], &w->sensors_m[0][1]);
        w->n_sensors = 1;
    }
    for (i = 0; i < w->n_sensors; ++i) {
        dem_map_to_cell(w->dem.gt, w->sensors_m[i][0], w->sensors_m[i][1], &col, &row);
        if (fabs(col) > 1e6 || fabs(row) > 1e6) {
            snprintf(err, err_len, "--sensors: %.3f,%.3f is %.0f cells from the map (at most 1e6)",
                     w->sensors_m[i][0], w->sensors_m[i][1], fmax(fabs(col), fabs(row)));
            return -1;
        }
        w->sensors[i].x_cells = (float)col;
        w->sensors[i].y_cells = (float)row;
    }
    return 0;
}

/* A patch of few cells at the DEM's resolution (the paper's 2 m patch is
 * 21 x 21 cells at 0.1 m, 3 x 3 at 1 m) carries little to match: said on
 * stderr, the geometry kept as given. */
static void warn_small_patch(const selmap_opts_t *o, double cell)
{
    long n = (long)floor(o->patch_m / cell + 0.5);
    n = n % 2 == 0 ? n + 1 : n;
    if (n < SELMAP_PATCH_FEW_CELLS) {
        fprintf(stderr,
                "trn: warning: the %g m patch is %ld x %ld cells of %g m, few to match (the "
                "paper's is 21 x 21); --patch-m %g gives %d x %d\n",
                o->patch_m, n, n, cell, cell * SELMAP_PATCH_FEW_CELLS, SELMAP_PATCH_FEW_CELLS,
                SELMAP_PATCH_FEW_CELLS);
    }
}

int selmap_prepare(selmap_t *w, const char *dem_path, const selmap_opts_t *o, char *err,
                   size_t err_len)
{
    char why[768];

    memset(w, 0, sizeof *w);
    if (check_opts(w, o, err, err_len) != 0) {
        return CLI_BAD_INPUT;
    }
    if (dem_read(dem_path, (int)o->band, TRN_MAX_DIM, &w->dem, why, sizeof why) != 0) {
        snprintf(err, err_len, "--dem: %s", why);
        return CLI_BAD_INPUT;
    }
    if (w->dem.cell_m > (double)TRN_CELL_MAX_M) {
        snprintf(err, err_len, "cell size %g m is above the %g m the core accepts", w->dem.cell_m,
                 (double)TRN_CELL_MAX_M);
        goto fail;
    }
    if (select_rules(w, o, w->dem.cell_m, err, err_len) != 0 ||
        build_map(w, o, err, err_len) != 0 || sensor_cells(w, err, err_len) != 0) {
        goto fail;
    }
    warn_small_patch(o, w->dem.cell_m);
    /* Eq. 8: the model, or the error raster with the model where it has no data. */
    if (selmap_prob_global(o, &w->dem, &w->k, w->sensors, w->n_sensors, &w->map, &w->pg, &w->pgraw,
                           err, err_len) != 0) {
        goto fail;
    }
    return 0;

fail:
    selmap_free(w);
    return CLI_BAD_INPUT;
}

void selmap_print_config(const selmap_opts_t *o, const trn_map_cfg_t *cfg)
{
    trn_sigma_model_t gm;
    selmap_gerr_model(o, &gm);
    printf("map          %s: bin %.4g m x %d, high-pass %.4g m, s %.4g m\n", o->mo.config,
           (double)cfg->terrain.zbin_m, (int)cfg->terrain.nz, (double)cfg->terrain.highpass_half_m,
           (double)cfg->sigma_m);
    if (cfg->match == (int32_t)TRN_MATCH_HEIGHTS) {
        printf(
            "predicts     the height matcher: noise %.4g m + %.4g/m r^2, the DEM's error %.4g m\n",
            (double)cfg->noise_m, (double)cfg->noise_k_per_m, (double)gm.sigma_min_m);
        if (o->points_per_cell > 0.0) {
            printf("binned       %.4g points a cell: noise over them, their centroid's jitter\n",
                   o->points_per_cell);
        }
        return;
    }
    printf("predicts     the voxel matcher (eqs. 8-9, 6)\n");
    printf("global error %.4g m + %.4g/m r^2%s%s\n", (double)gm.sigma_min_m, (double)gm.k_per_m,
           o->gerr != NULL ? ", per-cell raster " : "", o->gerr != NULL ? o->gerr : "");
}
