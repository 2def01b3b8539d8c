/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/cmd_terrain.c - `trn terrain`: a synthetic Mars terrain
 * (Golombek & Rapp rocks on smooth relief) as a georeferenced GeoTIFF. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cmd_run.h"
#include "commands.h"
#include "dem_io.h"
#include "terrain_gen.h"
#include "trn/trn_config.h"

void cmd_terrain_params_default(cmd_terrain_params_t *p)
{
    memset(p, 0, sizeof *p);
    p->size = 256;
    p->cell = 0.1;
    p->k = 0.1;
    p->ratio = 0.5;
    p->relief = 0.05;
    p->seed = 1;
}

/* argv -> p. Returns CLI_OK, CLI_HELP (usage printed) or the usage / bad input status (message printed). */
static int terrain_parse(int argc, char **argv, cmd_terrain_params_t *p)
{
    cli_opt_t opts[] = {
        {"--out", CLI_STRING, &p->out, 0, 0, 1, "FILE.tif", "GeoTIFF to write", 0},
        {"--size-cells", CLI_LONG, &p->size, 8, TRN_MAX_DIM, 0, "N", "map side, cells", 0},
        {"--cell-m", CLI_DOUBLE, &p->cell, 0.001, 100.0, 0, "C", "cell size, metres", 0},
        {"--coverage", CLI_DOUBLE, &p->k, 0.01, 0.5, 0, "K",
         "rock coverage k of F_k(D) = k exp(-q(k) D)", 0},
        {"--seed", CLI_U64, &p->seed, 0, 0, 0, "S", "random seed", 0},
        {"--height-ratio", CLI_DOUBLE, &p->ratio, 0.05, 2.0, 0, "R",
         "rock height / diameter (0.5: hemispheres)", 0},
        {"--min-diameter-m", CLI_DOUBLE, &p->dmin, 0.001, 100.0, 0, "D",
         "smallest rock drawn (default 2 cells)", 0},
        {"--max-diameter-m", CLI_DOUBLE, &p->dmax, 0.001, 100.0, 0, "D",
         "largest rock drawn (default ln(1e4)/q(k))", 0},
        {"--relief-m", CLI_DOUBLE, &p->relief, 0.0, 100.0, 0, "A",
         "RMS of the smooth background relief", 0},
        {"--origin", CLI_XY, p->origin, 0, 0, 0, "X,Y", "map coordinates of the south-west corner",
         0},
        {"--crs", CLI_STRING, &p->crs, 0, 0, 0, "SRS",
         "CRS to tag the file with (EPSG:n, IAU_2015:n, WKT, PROJ; default none)", 0},
        {"--json", CLI_FLAG, &p->json, 0, 0, 0, NULL,
         "print one JSON object instead of the summary", 0},
    };
    cli_cmd_t cmd = {
        "terrain", "Write a synthetic Mars terrain: Golombek & Rapp (1997) rocks on smooth relief.",
        "Rocks are half-ellipsoids of diameter D and height R*D drawn from the cumulative\n"
        "fractional area F_k(D) = k exp(-(1.79 + 0.152/k) D), D in metres (docs/method.md).\n"
        "The GeoTIFF is north-up, float32 metres, no-data NaN.",
        opts, sizeof opts / sizeof opts[0]};
    return cli_parse(&cmd, argc, argv);
}

/* The generator's parameters from p; NULL, or the reason they are refused. */
static const char *terrain_gen_params(const cmd_terrain_params_t *p, tg_params_t *g, char *err,
                                      size_t err_len)
{
    const char *why;
    tg_default(g, (int)p->size, (int)p->size, p->cell);
    g->coverage_k = p->k;
    g->height_ratio = p->ratio;
    g->d_min_m = p->dmin > 0.0 ? p->dmin : 2.0 * p->cell;
    g->d_max_m = p->dmax > 0.0 ? p->dmax : tg_auto_d_max(p->k);
    g->relief_m = p->relief;
    g->seed = p->seed;
    if (g->d_max_m < g->d_min_m) {
        snprintf(err, err_len,
                 "largest rock diameter %g m is below the smallest %g m (see --min-diameter-m, "
                 "--max-diameter-m)",
                 g->d_max_m, g->d_min_m);
        return err;
    }
    if ((why = tg_check(g)) != NULL) {
        snprintf(err, err_len, "%s", why);
        return err;
    }
    return NULL;
}

/* Realised rock area: rocks centred on the map. */
static double rock_area(const cmd_terrain_params_t *p, const tg_rock_t *rocks, size_t n)
{
    double ext = (double)p->size * p->cell, area_in = 0.0;
    size_t i;
    for (i = 0; i < n; ++i) {
        if (rocks[i].x_m >= 0.0 && rocks[i].x_m < ext && rocks[i].y_m >= 0.0 &&
            rocks[i].y_m < ext) {
            area_in += 0.25 * 3.14159265358979323846 * rocks[i].d_m * rocks[i].d_m;
        }
    }
    return area_in / (ext * ext);
}

int cmd_terrain_run(const cmd_terrain_params_t *p, cmd_terrain_result_t *r, char *err,
                    size_t err_len)
{
    tg_rock_t *rocks = NULL;
    size_t n, n2;
    float *dem = NULL;
    double gt[6];
    char *wkt = NULL;
    int rc = CLI_BAD_INPUT;

    memset(r, 0, sizeof *r);
    if (terrain_gen_params(p, &r->p, err, err_len) != NULL) {
        return CLI_BAD_INPUT;
    }
    if (p->crs != NULL && (wkt = dem_srs_to_wkt(p->crs, err, err_len)) == NULL) {
        return CLI_BAD_INPUT;
    }
    n = tg_draw_rocks(&r->p, NULL, 0);
    rocks = malloc((n + 1) * sizeof *rocks);
    dem = malloc((size_t)p->size * (size_t)p->size * sizeof *dem);
    if (rocks == NULL || dem == NULL) {
        snprintf(err, err_len, "out of memory for %zu rocks on %ld x %ld cells", n, p->size,
                 p->size);
        goto done;
    }
    n2 = tg_draw_rocks(&r->p, rocks, n);
    if (n2 != n) {
        snprintf(err, err_len, "internal error: rock draw not repeatable (%zu vs %zu)", n, n2);
        goto done;
    }
    if (p->progress != NULL) {
        p->progress(p->progress_ctx, 0, (long)n + p->size);
    }
    tg_render(&r->p, rocks, n, dem, p->progress, p->progress_ctx);
    r->n_rocks = n;
    r->area_fraction = rock_area(p, rocks, n);
    r->model_fraction = tg_cum_area(p->k, r->p.d_min_m) - tg_cum_area(p->k, r->p.d_max_m);

    /* North-up: the top-left corner is (origin x, origin y + side). */
    gt[0] = p->origin[0];
    gt[1] = p->cell;
    gt[2] = 0.0;
    gt[3] = p->origin[1] + (double)p->size * p->cell;
    gt[4] = 0.0;
    gt[5] = -p->cell;
    if (dem_write_gtiff(p->out, dem, (int)p->size, (int)p->size, gt, wkt, err, err_len) == 0) {
        rc = CLI_OK;
    }
done:
    free(dem);
    free(rocks);
    free(wkt);
    return rc;
}

static void terrain_report(const cmd_terrain_params_t *p, const cmd_terrain_result_t *r)
{
    if (p->json) {
        json_t j;
        json_begin(&j, stdout);
        json_str(&j, "file", p->out);
        json_int(&j, "width", p->size);
        json_int(&j, "height", p->size);
        json_num(&j, "cell_m", p->cell);
        json_obj(&j, "origin");
        json_num(&j, "x_m", p->origin[0]);
        json_num(&j, "y_m", p->origin[1]);
        json_obj_end(&j);
        json_num(&j, "coverage_k", p->k);
        json_num(&j, "q_per_m", tg_q(p->k));
        json_num(&j, "height_ratio", p->ratio);
        json_num(&j, "d_min_m", r->p.d_min_m);
        json_num(&j, "d_max_m", r->p.d_max_m);
        json_num(&j, "relief_m", p->relief);
        json_int(&j, "seed", (long long)p->seed);
        json_int(&j, "rocks", (long long)r->n_rocks);
        json_num(&j, "rock_area_fraction", r->area_fraction);
        json_num(&j, "model_area_fraction", r->model_fraction);
        json_end(&j);
    } else {
        printf("wrote %s: %ld x %ld cells of %g m, origin (%g, %g) m, seed %llu\n", p->out, p->size,
               p->size, p->cell, p->origin[0], p->origin[1], (unsigned long long)p->seed);
        printf("rocks: %zu with D in [%.3f, %.3f] m, height %.2f D; area fraction %.4f (model "
               "F_k(Dmin)-F_k(Dmax) "
               "= %.4f, k = %g)\n",
               r->n_rocks, r->p.d_min_m, r->p.d_max_m, p->ratio, r->area_fraction,
               r->model_fraction, p->k);
    }
}

int trn_cmd_terrain(int argc, char **argv)
{
    cmd_terrain_params_t p;
    cmd_terrain_result_t r;
    progress_lazy_t prog;
    char err[CMD_ERR_LEN];
    int rc;

    cmd_terrain_params_default(&p);
    rc = terrain_parse(argc, argv, &p);
    if (rc != CLI_OK) {
        return rc == CLI_HELP ? 0 : rc;
    }
    progress_lazy_init(&prog, "terrain");
    p.progress = progress_lazy_update;
    p.progress_ctx = &prog;
    rc = cmd_terrain_run(&p, &r, err, sizeof err);
    progress_lazy_end(&prog);
    if (rc != CLI_OK) {
        cli_fail("terrain", "%s", err);
        return rc;
    }
    terrain_report(&p, &r);
    return 0;
}
