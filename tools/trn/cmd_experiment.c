/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/cmd_experiment.c - `trn experiment`: the paper's section 5 Monte
 * Carlo, localization with and without landmark selection (experiment.h;
 * docs/method.md section 8). */
#define _POSIX_C_SOURCE 200112L /* clock_gettime */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include <stdlib.h>

#include "cli.h"
#include "cmd_run.h"
#include "commands.h"
#include "dem_io.h"
#include "experiment.h"
#include "mapopt.h"
#include "selmap.h"

/* The map configuration from the options (exp_params_t.map_cfg); ctx: the result. */
static int map_cfg_cb(void *ctx, const float *dem, int width, int height, double cell_m,
                      trn_map_cfg_t *cfg, char *err, size_t err_len)
{
    cmd_experiment_result_t *r = ctx;
    if (mapopt_config(r->mo, dem, width, height, cell_m, cfg, &r->sigma_h, err, err_len) != 0) {
        return -1;
    }
    if (cfg->match == TRN_MATCH_HEIGHTS) {
        /* the height matcher (trn_localize_dem) as configured; it always refines */
        cfg->refine = 1;
        return 0;
    }
    /* what the voxel experiment does, whatever the configuration would do in
     * trn localize: sampled points, the voxel search (trn_localize_points), a
     * local DEM (--sensor dem) filtered on its own, no refinement, no
     * acceptance limit; the JSON's map_config says so */
    cfg->refine = 0;
    cfg->noise_auto = 0;
    cfg->local_highpass = TRN_LOCAL_HP_BOX;
    cfg->max_failure_prob = 1.0f;
    return 0;
}

static int on_progress(void *ctx, long done, long total)
{
    progress_lazy_update(ctx, done, total);
    return 0;
}

static void json_ci(json_t *j, const char *key, const double ci[2])
{
    /* "key": [low, high] (null for a non-finite bound) */
    fprintf(j->out, "%s", j->first[j->depth] ? "" : ", ");
    j->first[j->depth] = 0;
    json_write_string(j->out, key);
    if (isfinite(ci[0]) && isfinite(ci[1])) {
        fprintf(j->out, ": [%.17g, %.17g]", ci[0], ci[1]);
    } else {
        fprintf(j->out, ": [null, null]");
    }
}

static void json_u64(json_t *j, const char *key, uint64_t v)
{
    /* json_int takes a signed value: seeds above 2^63 would print negative */
    fprintf(j->out, "%s", j->first[j->depth] ? "" : ", ");
    j->first[j->depth] = 0;
    json_write_string(j->out, key);
    fprintf(j->out, ": %llu", (unsigned long long)v);
}

static void json_arm(json_t *j, const char *key, const exp_arm_t *a, long trials, int heights)
{
    json_obj(j, key);
    json_int(j, "localizations", a->localizations);
    json_int(j, "localizations_per_trial", a->localizations / trials);
    json_int(j, "successes", a->successes);
    json_num(j, "success_rate", a->st.rate);
    json_ci(j, "ci95", a->st.rate_ci);
    json_num(j, "effective_n", a->st.n_eff);
    json_num(j, "mean_error_m", a->st.mean);
    json_ci(j, "mean_error_ci95", a->st.mean_ci);
    json_num(j, "sd_error_m", a->st.sd);
    json_num(j, "success_rate_1_cell", (double)a->success_1cell / (double)a->localizations);
    json_num(j, "success_rate_5_cells", (double)a->success_5cells / (double)a->localizations);
    json_int(j, "no_target", a->no_target);
    json_int(j, "empty_local_maps", a->no_points);
    json_int(j, "ill_conditioned", a->ill_conditioned);
    json_num(j, "mean_local_points", a->mean_points);
    json_num(j, "mean_target_range_m", a->mean_range_m);
    if (heights) { /* trn_localize_dem's status: accepted answers, and the wrong ones among them */
        json_int(j, "fixes", a->fixes);
        json_int(j, "wrong_fixes", a->wrong_fixes);
        json_int(j, "ambiguous", a->ambiguous);
        json_int(j, "noise_rescaled", a->noise_rescaled);
    }
    json_obj_end(j);
}

static void print_arm(const char *name, const exp_arm_t *a)
{
    printf("%-18s %6ld %7ld  %6.1f %%  [%5.1f, %5.1f]   %6.3f m  [%.3f, %.3f]\n", name,
           a->localizations, a->successes, 100.0 * a->st.rate, 100.0 * a->st.rate_ci[0],
           100.0 * a->st.rate_ci[1], a->st.mean, a->st.mean_ci[0], a->st.mean_ci[1]);
}

void cmd_experiment_params_default(cmd_experiment_params_t *p)
{
    exp_params_t e;
    memset(p, 0, sizeof *p);
    exp_params_default(&e);
    selmap_opts_default(&p->so, 2);
    p->so.mo.config = SELMAP_EXPERIMENT_MAP_CONFIG;
    p->band = 1;
    p->foot = -1.0;
    p->sensor = "prob";
    p->trials = e.trials;
    p->seed = e.seed;
    p->tseed = e.terrain_seed;
    p->k = e.coverage_k;
    p->relief = e.relief_m;
    p->size = e.size_cells;
    p->window = e.window_m;
    p->prior = e.prior_error_m;
    p->spacing = e.grid_spacing_m;
    p->succ = e.success_cells;
    p->heading_search = e.select_heading_search;
}

/* With the height matcher the local map is the DEM's heights with the noise
 * model: the voxel search's sensor options and the heading error (whose
 * 3-DOF search is the voxel search's) do not apply. 0, or -1 with the reason. */
static int experiment_heights_usage(const cmd_experiment_params_t *p, cli_opt_t *opts,
                                    size_t n_opts, char *err, size_t err_len)
{
    /* the voxel search's sensor options, then eq. 8's inputs beyond its
     * constant (the voxel prediction's P_G only) */
    static const char *const vox_sensor =
        "shapes the voxel search's local map (--match voxel); the height matcher senses the "
        "DEM's heights with the noise model (--noise-m, --noise-k)";
    static const char *const vox_pg =
        "applies to the voxel prediction (--match voxel); the height matcher's selection takes "
        "the DEM's error as one sd, --global-sigma-m";
    static const struct {
        const char *opt;
        int pg; /* 1: eq. 8's input, 0: the sensor's */
    } refused[] = {
        {"--sensor", 0}, {"--height-noise-m", 0}, {"--global-sigma-k", 1}, {"--global-error", 1}};
    size_t i;
    if (!mapopt_heights(&p->so.mo)) {
        return 0;
    }
    for (i = 0; i < sizeof refused / sizeof refused[0]; ++i) {
        if (cli_find(opts, n_opts, refused[i].opt)->seen) {
            snprintf(err, err_len, "%s %s", refused[i].opt, refused[i].pg ? vox_pg : vox_sensor);
            return -1;
        }
    }
    if (p->heading_err > 0.0) {
        snprintf(err, err_len,
                 "--heading-error-deg: the experiment's 3-DOF search is the voxel search's "
                 "(--match voxel); the height matcher runs without a heading error here");
        return -1;
    }
    return 0;
}

/* The usage rules between options: the terrain's options without --dem, --global-error with it. */
static int experiment_usage(cmd_experiment_params_t *p, cli_opt_t *opts, size_t n_opts)
{
    static const char *const synth[] = {"--coverage", "--terrain-seed", "--min-diameter-m",
                                        "--relief-m", "--size-cells"};
    char err[512];
    size_t i;
    if (p->dem_path != NULL && !cli_find(opts, n_opts, "--map-config")->seen) {
        p->so.mo.config = "auto";
    }
    if (mapopt_check_use(&p->so.mo, MAPOPT_USE_EXPERIMENT, err, sizeof err) != 0 ||
        experiment_heights_usage(p, opts, n_opts, err, sizeof err) != 0) {
        fprintf(stderr, "trn experiment: %s\n", err);
        return CLI_USAGE;
    }
    if (!(p->heading_err > 0.0)) { /* no heading error: no 3-DOF search to shape */
        static const char *const h3[] = {"--heading-window-deg", "--select-heading-search"};
        for (i = 0; i < sizeof h3 / sizeof h3[0]; ++i) {
            if (cli_find(opts, n_opts, h3[i])->seen) {
                fprintf(stderr,
                        "trn experiment: %s shapes the 3-DOF search, which runs only with "
                        "--heading-error-deg above 0\n",
                        h3[i]);
                return CLI_USAGE;
            }
        }
    }
    if (p->dem_path == NULL && cli_find(opts, n_opts, "--band")->seen) {
        fprintf(stderr, "trn experiment: --band picks a band of --dem; it does not apply without "
                        "--dem\n");
        return CLI_USAGE;
    }
    if (p->dem_path != NULL) {
        for (i = 0; i < sizeof synth / sizeof synth[0]; ++i) {
            if (cli_find(opts, n_opts, synth[i])->seen) {
                fprintf(stderr,
                        "trn experiment: %s shapes the generated terrain; it does not apply with "
                        "--dem\n",
                        synth[i]);
                return CLI_USAGE;
            }
        }
    } else if (p->so.gerr != NULL) {
        fprintf(stderr,
                "trn experiment: --global-error needs --dem (the raster lies on the DEM's grid)\n");
        return CLI_USAGE;
    }
    p->seen_tseed = cli_find(opts, n_opts, "--terrain-seed")->seen;
    p->seen_dmin = cli_find(opts, n_opts, "--min-diameter-m")->seen;
    p->seen_window = cli_find(opts, n_opts, "--window-m")->seen;
    p->seen_prior = cli_find(opts, n_opts, "--prior-error-m")->seen;
    p->seen_spacing = cli_find(opts, n_opts, "--grid-spacing-m")->seen;
    return CLI_OK;
}

/* Help texts whose defaults depend on the terrain: the selection lengths
 * (the core's, trn_select_cfg_default in p->so, scaled by cell / 0.1 m), the
 * global map's error (world_prob in experiment.c: trn_sigma_global_default,
 * its constant scaled, its r^2 term 0 on a --dem) and the map configuration;
 * h holds the texts, written into opts. */
#define EXP_N_HELP 6
static void experiment_help(const cmd_experiment_params_t *p, cli_opt_t *opts, size_t n_opts,
                            char h[EXP_N_HELP][112])
{
    trn_sigma_model_t gm;
    trn_sigma_global_default(&gm);
    snprintf(h[0], sizeof h[0], "nearest target (default %g m at 0.1 m cells; scaled on a --dem)",
             p->so.min_range_m);
    snprintf(h[1], sizeof h[1], "farthest target (default %g m at 0.1 m cells; scaled on a --dem)",
             p->so.max_range_m);
    snprintf(h[2], sizeof h[2],
             "side of the sensed patch (default %g m at 0.1 m cells; scaled on a --dem)",
             p->so.patch_m);
    snprintf(h[3], sizeof h[3],
             "rover footprint radius no patch may touch (default %g m at 0.1 m cells; scaled on a "
             "--dem)",
             p->so.footprint_m);
    snprintf(h[4], sizeof h[4],
             "global map's error at its sensing position, m (eq. 8; default %g at 0.1 m cells; "
             "scaled on a --dem)",
             (double)gm.sigma_min_m);
    snprintf(h[5], sizeof h[5],
             "global map's error growth with squared range from the map's centre, 1/m (default %g; "
             "0 on a --dem)",
             (double)gm.k_per_m);
    cli_find(opts, n_opts, "--global-sigma-m")->help = h[4];
    cli_find(opts, n_opts, "--global-sigma-k")->help = h[5];
    cli_find(opts, n_opts, "--map-config")->help =
        "map configuration: paper (as in the paper, scaled to the cell, the voxel matcher; default "
        "on the generated terrain) or auto (from the DEM, the height matcher, docs/method.md 9; "
        "default with --dem)";
    cli_find(opts, n_opts, "--match")->help =
        "the localizer: voxel (the paper's: local maps sampled from the probability map, the voxel "
        "search) or heights (the DEM's heights with the noise model, trn_localize_dem) (default: "
        "--map-config's)";
    cli_find(opts, n_opts, "--noise-m")->help =
        "height noise of the local maps, constant part, m: with --match heights the simulated "
        "sensor's and the matcher's model; with voxel it sets only auto's height bin "
        "(default " MAPOPT_STR(MAPOPT_NOISE_M) ")";
    cli_find(opts, n_opts, "--noise-k")->help = "height noise of the local maps, range-squared "
                                                "part, 1/m (as --noise-m; default " MAPOPT_STR(
                                                    MAPOPT_NOISE_K_PER_CELL) "/cell)";
    cli_find(opts, n_opts, "--max-failure-prob")->help =
        "with --match heights: an answer whose failure probability is above P is 'ambiguous', not "
        "a fix (the arms' fixes, wrong_fixes, ambiguous; default " MAPOPT_STR(
            TRN_MAP_MAX_FAILURE_PROB_AUTO) " with auto, 1 = never with paper)";
}

/* argv -> p. Returns CLI_OK, CLI_HELP (usage printed) or the usage / bad input status (message printed). */
static int experiment_parse(int argc, char **argv, cmd_experiment_params_t *p)
{
    char h[EXP_N_HELP][112];
#define EXP_N_OWN 23
    cli_opt_t own[EXP_N_OWN] = {
        {"--trials", CLI_LONG, &p->trials, 1, 1000000, 0, "N", "trials", 0},
        {"--seed", CLI_U64, &p->seed, 0, 0, 0, "S",
         "seed of the trials and, unless --terrain-seed, of the terrain", 0},
        {"--dem", CLI_STRING, &p->dem_path, 0, 0, 0, "FILE",
         "run on this DEM (projected, metres; at most 1024 x 1024) instead of a generated terrain",
         0},
        {"--band", CLI_LONG, &p->band, 1, 65535, 0, "N", "band of --dem", 0},
        {"--coverage", CLI_DOUBLE, &p->k, 0.01, 0.5, 0, "K",
         "rock coverage k of the terrain (as `trn terrain`)", 0},
        {"--terrain-seed", CLI_U64, &p->tseed, 0, 0, 0, "S",
         "seed of the terrain (default: --seed)", 0},
        {"--min-diameter-m", CLI_DOUBLE, &p->dmin, 0.1, 10.0, 0, "D",
         "smallest rock of the terrain (default 2 cells, as `trn terrain`)", 0},
        {"--relief-m", CLI_DOUBLE, &p->relief, 0.0, 10.0, 0, "A",
         "RMS of the terrain's smooth background relief (as `trn terrain`)", 0},
        {"--size-cells", CLI_LONG, &p->size, 64, 1024, 0, "N",
         "terrain side, cells of 0.1 m (as `trn terrain`)", 0},
        {"--window-m", CLI_DOUBLE, &p->window, 1e-6, 1e6, 0, "R",
         "localization window: prior +-R m per axis (at 0.1 m cells; scaled on a --dem)", 0},
        {"--prior-error-m", CLI_DOUBLE, &p->prior, 0.0, 1e6, 0, "E",
         "prior offset from the truth, uniform in +-E m per axis (at 0.1 m cells; scaled on a "
         "--dem)",
         0},
        {"--grid-spacing-m", CLI_DOUBLE, &p->spacing, 0.0, 1e6, 0, "G",
         "spacing of the nine targets without selection (one patch at 0.1 m cells; scaled on a "
         "--dem)",
         0},
        {"--min-range-m", CLI_DOUBLE, &p->minr, 1e-6, 1e6, 0, "R", h[0], 0},
        {"--max-range-m", CLI_DOUBLE, &p->maxr, 1e-6, 1e6, 0, "R", h[1], 0},
        {"--patch-m", CLI_DOUBLE, &p->patch, 1e-6, 1e6, 0, "S", h[2], 0},
        {"--footprint-m", CLI_DOUBLE, &p->foot, 0.0, 1e6, 0, "R", h[3], 0},
        {"--success-cells", CLI_DOUBLE, &p->succ, 0.1, 100.0, 0, "C", "success: error <= C cells",
         0},
        {"--sensor", CLI_STRING, &p->sensor, 0, 0, 0, "prob|dem",
         "local-map model: prob = sampled from the probability map (the paper's, default); dem = "
         "the true DEM with height noise (diagnostic)",
         0},
        {"--height-noise-m", CLI_DOUBLE, &p->hnoise, 0.0, 1.0, 0, "H",
         "with --sensor dem: Gaussian height noise per cell, m", 0},
        {"--heading-error-deg", CLI_DOUBLE, &p->heading_err, 0.0, 30.0, 0, "S",
         "each trial's local maps turned by a heading error drawn N(0, S); selection counts its "
         "lever arm, and the 3-DOF search (x, y, heading) localizes beside the x-y one",
         0},
        {"--heading-window-deg", CLI_DOUBLE, &p->heading_win, 0.0, 180.0, 0, "W",
         "the 3-DOF search's half-window (0: 3 x --heading-error-deg)", 0},
        {"--select-heading-search", CLI_LONG, &p->heading_search, 0, 1, 0, "0|1",
         "the 3-DOF arm with selection ranks its own target for a heading search (1; "
         "docs/method.md "
         "4), or senses the x-y arm's (0)",
         0},
        {"--json", CLI_FLAG, &p->json, 0, 0, 0, NULL, "print one JSON object instead of the table",
         0},
    };
    cli_opt_t opts[EXP_N_OWN + SELMAP_N_GERR_OPTS + MAPOPT_N];
    const size_t n_opts = sizeof opts / sizeof opts[0];
    cli_cmd_t cmd = {
        "experiment",
        "The paper's section 5 Monte Carlo: localization success and accuracy with and without "
        "landmark selection.",
        "Terrain: `trn terrain --coverage K --seed S` (256 x 256 cells of 0.1 m), or --dem FILE.\n"
        "Per trial: random start and finish, the rover at the finish with a prior off by up to\n"
        "--prior-error-m; with selection it senses trn_select's best target, without it senses\n"
        "the target midway between start and prior and the eight around it (each a localization\n"
        "of its own). With the voxel matcher (--match voxel, --map-config paper) local maps are\n"
        "sampled from the probability map (eqs. 8-9) and localized by the voxel search; with the\n"
        "height matcher (--match heights, --map-config auto) a local map is the DEM's true "
        "heights\n"
        "over the sensed patch plus Gaussian noise of sd --noise-m + --noise-k r^2, localized by\n"
        "trn_localize_dem, and the selection predicts it (trn select's height prediction).\n"
        "Either in the prior window; success = error <= --success-cells.\n"
        "Rates with Wilson 95 % intervals, mean error of the successes with t intervals\n"
        "(docs/method.md section 8). Seeded: the same options give the same output.\n"
        "Every length defaults to its value at the paper's 0.1 m cells scaled by cell / 0.1 m\n"
        "(the same experiment in cells), and so do the error models (constant x cell/0.1, r^2 term "
        "/\n"
        "(cell/0.1)); on the generated terrain the factor is 1. On a --dem the global map's error\n"
        "has no r^2 term unless --global-sigma-k gives one (an overhead DEM is sensed from no\n"
        "point on it). Map configuration: --map-config\n"
        "" SELMAP_EXPERIMENT_MAP_CONFIG " on the generated terrain, auto with --dem.",
        opts, 0};
    int rc;

    memcpy(opts, own, (EXP_N_OWN) * sizeof own[0]);
    selmap_gerr_opts(&p->so, opts + EXP_N_OWN);
    mapopt_cli(&p->so.mo, opts + EXP_N_OWN + SELMAP_N_GERR_OPTS);
    experiment_help(p, opts, n_opts, h);
    /* the localizer's options neither matcher reads here */
    cmd.n_opts = cli_remove(opts, n_opts, mapopt_not_taken(MAPOPT_USE_EXPERIMENT));
    rc = cli_parse(&cmd, argc, argv);
    return rc != CLI_OK ? rc : experiment_usage(p, opts, cmd.n_opts);
}

/* --dem and --global-error into r, the experiment's DEM fields of r->p. */
static int experiment_dem(const cmd_experiment_params_t *p, cmd_experiment_result_t *r, char *err,
                          size_t err_len)
{
    char why[768];
    size_t i;
    if (dem_read(p->dem_path, (int)p->band, 1024, &r->dem, why, sizeof why) != 0) {
        snprintf(err, err_len, "--dem: %s", why);
        return CLI_BAD_INPUT;
    }
    if (p->so.gerr != NULL && selmap_read_error(p->so.gerr, &r->dem, &r->gerr, err, err_len) != 0) {
        return CLI_BAD_INPUT;
    }
    for (i = 0; i < (size_t)r->dem.width * (size_t)r->dem.height; ++i) {
        r->n_nodata += !isfinite(r->dem.data[i]);
    }
    r->p.dem = r->dem.data;
    r->p.dem_width = r->dem.width;
    r->p.dem_height = r->dem.height;
    r->p.cell_m = r->dem.cell_m;
    r->p.global_error = r->gerr.data;
    r->f = r->dem.cell_m / 0.1;
    return CLI_OK;
}

/* The experiment's parameters (r->p) from the options; lengths scaled by r->f unless given. */
static void experiment_fill(const cmd_experiment_params_t *p, cmd_experiment_result_t *r)
{
    exp_params_t *e = &r->p;
    e->trials = p->trials;
    e->seed = p->seed;
    e->terrain_seed = p->seen_tseed ? p->tseed : p->seed;
    e->coverage_k = p->k;
    e->d_min_m = p->seen_dmin ? p->dmin : 0.0;
    e->relief_m = p->relief;
    e->size_cells = (int)p->size;
    e->window_m = p->seen_window ? p->window : p->window * r->f;
    e->prior_error_m = p->seen_prior ? p->prior : p->prior * r->f;
    e->grid_spacing_m = p->seen_spacing ? p->spacing : p->spacing * r->f;
    e->min_range_m = p->minr;
    e->max_range_m = p->maxr;
    e->patch_m = p->patch;
    e->footprint_m = p->foot;
    e->success_cells = p->succ;
    e->height_noise_m = p->hnoise;
    e->heading_error_deg = p->heading_err;
    e->heading_window_deg = p->heading_win;
    e->select_heading_search = p->heading_search;
    e->global_sigma_m = p->so.gsig_m;
    e->global_sigma_k = p->so.gsig_k;
    r->mo = &p->so.mo;
    r->sigma_h = NAN;
    e->map_cfg = map_cfg_cb;
    e->map_cfg_ctx = r;
}

int cmd_experiment_run(const cmd_experiment_params_t *p, cmd_experiment_result_t *r, char *err,
                       size_t err_len)
{
    struct timespec t0, t1;
    const char *why;
    int rc;

    memset(r, 0, sizeof *r);
    exp_params_default(&r->p);
    r->f = 1.0;
    if (strcmp(p->sensor, "prob") == 0) {
        r->p.sensor = EXP_SENSOR_PROB;
    } else if (strcmp(p->sensor, "dem") == 0) {
        r->p.sensor = EXP_SENSOR_DEM;
    } else {
        snprintf(err, err_len, "--sensor: '%s' is not prob or dem", p->sensor);
        return CLI_BAD_INPUT;
    }
    if (p->dem_path != NULL && (rc = experiment_dem(p, r, err, err_len)) != CLI_OK) {
        return rc;
    }
    experiment_fill(p, r);
    if ((why = exp_params_check(&r->p)) != NULL) {
        snprintf(err, err_len, "%s", why);
        return CLI_BAD_INPUT;
    }
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (p->progress != NULL) {
        p->progress(p->progress_ctx, 0, p->trials);
    }
    rc = exp_run(&r->p, &r->r, p->progress, p->progress_ctx, err, err_len);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    if (rc != 0) {
        if (p->dem_path != NULL) {
            char why2[CMD_ERR_LEN];
            snprintf(why2, sizeof why2, "%s", err);
            snprintf(err, err_len, "--dem: %s", why2);
        }
        return CLI_BAD_INPUT;
    }
    r->secs = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    r->gain = 1.0 - r->r.with.st.mean / r->r.without.st.mean;
    return CLI_OK;
}

void cmd_experiment_result_free(cmd_experiment_result_t *r)
{
    dem_free(&r->dem);
    dem_free(&r->gerr);
}

static void experiment_json_terrain(json_t *j, const cmd_experiment_params_t *p,
                                    const cmd_experiment_result_t *r)
{
    json_obj(j, "terrain");
    if (p->dem_path != NULL) {
        json_str(j, "dem", p->dem_path);
        json_int(j, "width", r->dem.width);
        json_int(j, "height", r->dem.height);
        json_num(j, "cell_m", r->p.cell_m);
        json_int(j, "no_data_cells", (long long)r->n_nodata);
        json_num(j, "scale", r->f);
    } else {
        json_int(j, "size_cells", p->size);
        json_num(j, "cell_m", r->p.cell_m);
        json_num(j, "coverage_k", p->k);
        json_u64(j, "seed", r->p.terrain_seed);
        json_num(j, "d_min_m", r->r.d_min_m);
        json_num(j, "relief_m", r->p.relief_m);
        json_int(j, "rocks", (long long)r->r.rocks);
    }
    json_obj_end(j);
}

static void experiment_json_parameters(json_t *j, const cmd_experiment_result_t *r)
{
    const exp_params_t *e = &r->p;
    const exp_result_t *x = &r->r;
    json_obj(j, "parameters");
    json_int(j, "patch_cells", x->patch_cells);
    json_num(j, "window_m", e->window_m);
    json_num(j, "min_range_m", x->scfg.min_range_m);
    json_num(j, "max_range_m", x->scfg.max_range_m);
    json_num(j, "patch_m", x->scfg.patch_m);
    json_num(j, "footprint_m", x->scfg.footprint_radius_m);
    json_num(j, "local_sigma_m", x->scfg.local_sigma.sigma_min_m);
    json_num(j, "local_sigma_k_per_m", x->scfg.local_sigma.k_per_m);
    json_int(j, "window_cells", x->window_cells);
    json_num(j, "prior_error_m", e->prior_error_m);
    json_num(j, "grid_spacing_m", x->grid_cells * e->cell_m);
    json_num(j, "success_radius_m", x->success_radius_m);
    if (x->heights) {
        json_str(j, "sensor", "heights");
        json_str(j, "sensor_model",
                 "the DEM's true heights over the sensed patch + Gaussian noise of sd noise_m + "
                 "noise_k_per_m r^2 (map_config), r metres from the rover");
    } else {
        json_str(j, "sensor", e->sensor == EXP_SENSOR_PROB ? "prob" : "dem");
        json_str(
            j, "sensor_model",
            e->sensor == EXP_SENSOR_PROB
                ? "each voxel of the sensed patch occupied with probability min(P, 1), eqs. 8-9"
                : "true DEM + Gaussian height noise per cell, high-passed and binned on its "
                  "own");
    }
    json_num(j, "height_noise_m", e->height_noise_m);
    json_str(j, "global_sensing_position", "map centre");
    json_obj_end(j);
}

static void experiment_report_json(const cmd_experiment_params_t *p,
                                   const cmd_experiment_result_t *r)
{
    selmap_opts_t g = p->so;
    json_t j;
    json_begin(&j, stdout);
    json_int(&j, "trials", p->trials);
    json_u64(&j, "seed", p->seed);
    json_str(&j, "localizer", r->r.heights ? "heights" : "voxel");
    experiment_json_terrain(&j, p, r);
    experiment_json_parameters(&j, r);
    g.gsig_m = r->r.global_sigma.sigma_min_m; /* the model used (scaled when not given) */
    g.gsig_k = r->r.global_sigma.k_per_m;
    selmap_json_config(&j, &g, &r->r.map_cfg, r->sigma_h);
    json_int(&j, "draws", r->r.draws);
    json_num(&j, "mean_traverse_m", r->r.mean_traverse_m);
    json_arm(&j, "with_selection", &r->r.with, p->trials, r->r.heights);
    json_arm(&j, "without_selection", &r->r.without, p->trials, r->r.heights);
    json_num(&j, "accuracy_gain", r->gain);
    if (r->p.heading_error_deg > 0.0) {
        json_obj(&j, "heading");
        json_num(&j, "error_deg", r->p.heading_error_deg);
        json_num(&j, "window_deg", r->r.heading_window_deg);
        json_num(&j, "selection_sigma_heading_rad", (double)r->r.scfg.sigma_heading_rad);
        json_int(&j, "select_heading_search", r->p.select_heading_search);
        json_int(&j, "trials_3dof_other_target", r->r.with3_other_target);
        json_arm(&j, "with_selection_3dof", &r->r.with3, p->trials, 0);
        json_arm(&j, "without_selection_3dof", &r->r.without3, p->trials, 0);
        json_obj_end(&j);
    }
    json_end(&j);
}

static void experiment_report_text(const cmd_experiment_params_t *p,
                                   const cmd_experiment_result_t *r)
{
    const exp_params_t *e = &r->p;
    const exp_result_t *x = &r->r;
    if (p->dem_path != NULL) {
        printf("trn experiment: %ld trials, seed %llu; DEM %s, %d x %d cells of %g m (%zu "
               "no-data), lengths x %g\n",
               p->trials, (unsigned long long)p->seed, p->dem_path, r->dem.width, r->dem.height,
               e->cell_m, r->n_nodata, r->f);
    } else {
        printf("trn experiment: %ld trials, seed %llu; terrain %ld x %ld cells of %g m, k = %g, "
               "seed %llu, %zu rocks\n",
               p->trials, (unsigned long long)p->seed, p->size, p->size, e->cell_m, p->k,
               (unsigned long long)e->terrain_seed, x->rocks);
    }
    printf("sensor: %s\n", x->heights ? "the DEM's heights + noise of sd noise_m + noise_k r^2, "
                                        "localized by the height matcher (trn_localize_dem)"
                           : e->sensor == EXP_SENSOR_PROB
                               ? "local maps sampled from the probability map (eqs. 8-9)"
                               : "true DEM + height noise (diagnostic, not the paper's)");
    printf("patch %d cells, window +-%g m, prior error +-%g m, grid %g m, success <= %g m; mean "
           "traverse %.2f m\n",
           x->patch_cells, e->window_m, e->prior_error_m, x->grid_cells * e->cell_m,
           x->success_radius_m, x->mean_traverse_m);
    printf("targets %g..%g m, footprint %g m; map %s: bin %.4g m x %d, high-pass %.4g m, s %.4g m; "
           "global error %.4g m + %.4g/m r^2%s\n\n",
           (double)x->scfg.min_range_m, (double)x->scfg.max_range_m,
           (double)x->scfg.footprint_radius_m, p->so.mo.config, (double)x->map_cfg.terrain.zbin_m,
           (int)x->map_cfg.terrain.nz, (double)x->map_cfg.terrain.highpass_half_m,
           (double)x->map_cfg.sigma_m, (double)x->global_sigma.sigma_min_m,
           (double)x->global_sigma.k_per_m,
           p->so.gerr != NULL ? " (per-cell raster where it has data)" : "");
    printf("%-18s %6s %7s  %8s  %14s   %8s  %s\n", "", "locs", "success", "rate", "95 % CI",
           "mean err", "95 % CI (successes)");
    print_arm("with selection", &x->with);
    print_arm("without selection", &x->without);
    if (e->heading_error_deg > 0.0) {
        printf(
            "heading error N(0, %g deg); the 3-DOF search over +-%g deg on the same local maps:\n",
            e->heading_error_deg, x->heading_window_deg);
        print_arm("with sel., 3-DOF", &x->with3);
        if (e->select_heading_search == 1) {
            printf("  (its own selection for a heading search, method.md 4: another target in %ld "
                   "of %ld trials)\n",
                   x->with3_other_target, e->trials);
        }
        print_arm("without, 3-DOF", &x->without3);
    }
    if (x->heights) {
        printf("height matcher's status, with / without selection: fixes %ld / %ld (wrong %ld / "
               "%ld), ambiguous %ld / %ld, ill-conditioned %ld / %ld\n",
               x->with.fixes, x->without.fixes, x->with.wrong_fixes, x->without.wrong_fixes,
               x->with.ambiguous, x->without.ambiguous, x->with.ill_conditioned,
               x->without.ill_conditioned);
    }
    printf("\nsuccessful localizations %.1f %% more accurate with selection (paper: 97.8 %% vs "
           "29.5 %%, 15.3 %%)\n",
           100.0 * r->gain);
    printf("elapsed %.1f s\n", r->secs);
}

int trn_cmd_experiment(int argc, char **argv)
{
    cmd_experiment_params_t p;
    cmd_experiment_result_t r;
    progress_lazy_t prog;
    char err[CMD_ERR_LEN];
    int rc;

    cmd_experiment_params_default(&p);
    rc = experiment_parse(argc, argv, &p);
    if (rc != CLI_OK) {
        return rc == CLI_HELP ? 0 : rc;
    }
    progress_lazy_init(&prog, "experiment");
    p.progress = on_progress;
    p.progress_ctx = &prog;
    rc = cmd_experiment_run(&p, &r, err, sizeof err);
    progress_lazy_end(&prog);
    if (rc != CLI_OK) {
        cli_fail("experiment", "%s", err);
    } else if (p.json) {
        experiment_report_json(&p, &r);
    } else {
        experiment_report_text(&p, &r);
    }
    cmd_experiment_result_free(&r);
    return rc;
}
