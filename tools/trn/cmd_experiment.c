/* tools/trn/cmd_experiment.c - `trn experiment`: the paper's section 5 Monte
 * Carlo, localization with and without landmark selection (experiment.h;
 * docs/method.md section 8). */
#define _POSIX_C_SOURCE 200112L /* clock_gettime */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "commands.h"
#include "experiment.h"

static void on_progress(void *ctx, long done, long total) {
  ((progress_t *)ctx)->total = total;
  progress_update((progress_t *)ctx, done);
}

static void json_ci(json_t *j, const char *key, const double ci[2]) {
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

static void json_u64(json_t *j, const char *key, uint64_t v) {
  /* json_int takes a signed value: seeds above 2^63 would print negative */
  fprintf(j->out, "%s", j->first[j->depth] ? "" : ", ");
  j->first[j->depth] = 0;
  json_write_string(j->out, key);
  fprintf(j->out, ": %llu", (unsigned long long)v);
}

static void json_arm(json_t *j, const char *key, const exp_arm_t *a, long trials) {
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
  json_obj_end(j);
}

static void print_arm(const char *name, const exp_arm_t *a) {
  printf("%-18s %6ld %7ld  %6.1f %%  [%5.1f, %5.1f]   %6.3f m  [%.3f, %.3f]\n", name, a->localizations,
         a->successes, 100.0 * a->st.rate, 100.0 * a->st.rate_ci[0], 100.0 * a->st.rate_ci[1], a->st.mean,
         a->st.mean_ci[0], a->st.mean_ci[1]);
}

int trn_cmd_experiment(int argc, char **argv) {
  exp_params_t p;
  exp_result_t r;
  long trials, size;
  uint64_t seed, tseed;
  double k, dmin, relief, window, prior, spacing, succ;
  int json = 0;
  const char *sensor = "prob";
  double hnoise = 0.0;
  char err[512];
  progress_t prog;
  struct timespec t0, t1;
  double secs, gain;
  int rc;
  cli_opt_t opts[] = {
      {"--trials", CLI_LONG, &trials, 1, 1000000, 0, "N", "trials (default 1000)", 0},
      {"--seed", CLI_U64, &seed, 0, 0, 0, "S", "seed of the trials and, unless --terrain-seed, of the terrain (default 1)", 0},
      {"--coverage", CLI_DOUBLE, &k, 0.01, 0.5, 0, "K", "rock coverage k of the terrain (default 0.1, as `trn terrain`)", 0},
      {"--terrain-seed", CLI_U64, &tseed, 0, 0, 0, "S", "seed of the terrain (default: --seed)", 0},
      {"--min-diameter-m", CLI_DOUBLE, &dmin, 0.1, 10.0, 0, "D", "smallest rock of the terrain (default 2 cells, as `trn terrain`)", 0},
      {"--relief-m", CLI_DOUBLE, &relief, 0.0, 10.0, 0, "A", "RMS of the terrain's smooth background relief (default 0.05, as `trn terrain`)", 0},
      {"--size-cells", CLI_LONG, &size, 64, 1024, 0, "N", "terrain side, cells of 0.1 m (default 256, as `trn terrain`)", 0},
      {"--window-m", CLI_DOUBLE, &window, 0.1, 20.0, 0, "R", "localization window: prior +-R m per axis (default 2)", 0},
      {"--prior-error-m", CLI_DOUBLE, &prior, 0.0, 10.0, 0, "E", "prior offset from the truth, uniform in +-E m per axis (default 1)", 0},
      {"--grid-spacing-m", CLI_DOUBLE, &spacing, 0.0, 10.0, 0, "G", "spacing of the nine targets without selection (default 2 = one patch)", 0},
      {"--success-cells", CLI_DOUBLE, &succ, 0.1, 100.0, 0, "C", "success: error <= C cells (default 2)", 0},
      {"--sensor", CLI_STRING, &sensor, 0, 0, 0, "prob|dem", "local-map model: prob = sampled from the probability map (the paper's, default); dem = the true DEM with height noise (diagnostic)", 0},
      {"--height-noise-m", CLI_DOUBLE, &hnoise, 0.0, 1.0, 0, "H", "with --sensor dem: Gaussian height noise per cell, m (default 0)", 0},
      {"--json", CLI_FLAG, &json, 0, 0, 0, NULL, "print one JSON object instead of the table", 0},
  };
  cli_cmd_t cmd = {"experiment",
                   "The paper's section 5 Monte Carlo: localization success and accuracy with and without "
                   "landmark selection.",
                   "Terrain: `trn terrain --coverage K --seed S` (256 x 256 cells of 0.1 m). Per trial: random\n"
                   "start and finish, the rover at the finish with a prior off by up to --prior-error-m; with\n"
                   "selection it senses trn_select's best target, without it senses the target midway between\n"
                   "start and prior and the eight around it (each a localization of its own). Local maps are\n"
                   "sampled from the probability map (eqs. 8-9), localized in the prior window; success =\n"
                   "error <= --success-cells. Rates with Wilson 95 % intervals, mean error of the successes with\n"
                   "t intervals (docs/method.md section 8). Seeded: the same options give the same output.",
                   opts, sizeof opts / sizeof opts[0]};

  exp_params_default(&p);
  trials = p.trials;
  seed = p.seed;
  tseed = p.terrain_seed;
  k = p.coverage_k;
  dmin = 0.0;
  relief = p.relief_m;
  size = p.size_cells;
  window = p.window_m;
  prior = p.prior_error_m;
  spacing = p.grid_spacing_m;
  succ = p.success_cells;
  rc = cli_parse(&cmd, argc, argv);
  if (rc == CLI_HELP) {
    return 0;
  }
  if (rc != CLI_OK) {
    return rc;
  }
  p.trials = trials;
  p.seed = seed;
  p.terrain_seed = opts[3].seen ? tseed : seed;
  p.coverage_k = k;
  p.d_min_m = opts[4].seen ? dmin : 0.0;
  p.relief_m = relief;
  p.size_cells = (int)size;
  p.window_m = window;
  p.prior_error_m = prior;
  p.grid_spacing_m = spacing;
  p.success_cells = succ;
  p.height_noise_m = hnoise;
  if (strcmp(sensor, "prob") == 0) {
    p.sensor = EXP_SENSOR_PROB;
  } else if (strcmp(sensor, "dem") == 0) {
    p.sensor = EXP_SENSOR_DEM;
  } else {
    return cli_fail(cmd.name, "--sensor: '%s' is not prob or dem", sensor);
  }
  {
    const char *why = exp_params_check(&p);
    if (why != NULL) {
      return cli_fail(cmd.name, "%s", why);
    }
  }

  clock_gettime(CLOCK_MONOTONIC, &t0);
  progress_begin(&prog, "experiment", trials);
  rc = exp_run(&p, &r, on_progress, &prog, err, sizeof err);
  progress_end(&prog);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  if (rc != 0) {
    return cli_fail(cmd.name, "%s", err);
  }
  secs = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
  gain = 1.0 - r.with.st.mean / r.without.st.mean;

  if (json) {
    json_t j;
    json_begin(&j, stdout);
    json_int(&j, "trials", trials);
    json_u64(&j, "seed", seed);
    json_obj(&j, "terrain");
    json_int(&j, "size_cells", size);
    json_num(&j, "cell_m", p.cell_m);
    json_num(&j, "coverage_k", k);
    json_u64(&j, "seed", p.terrain_seed);
    json_num(&j, "d_min_m", r.d_min_m);
    json_num(&j, "relief_m", p.relief_m);
    json_int(&j, "rocks", (long long)r.rocks);
    json_obj_end(&j);
    json_obj(&j, "parameters");
    json_int(&j, "patch_cells", r.patch_cells);
    json_num(&j, "window_m", window);
    json_int(&j, "window_cells", r.window_cells);
    json_num(&j, "prior_error_m", prior);
    json_num(&j, "grid_spacing_m", r.grid_cells * p.cell_m);
    json_num(&j, "success_radius_m", r.success_radius_m);
    json_str(&j, "sensor", p.sensor == EXP_SENSOR_PROB ? "prob" : "dem");
    json_str(&j, "sensor_model", p.sensor == EXP_SENSOR_PROB
                                     ? "each voxel of the sensed patch occupied with probability min(P, 1), eqs. 8-9"
                                     : "true DEM + Gaussian height noise per cell, high-passed and binned on its own");
    json_num(&j, "height_noise_m", p.height_noise_m);
    json_str(&j, "global_sensing_position", "map centre");
    json_obj_end(&j);
    json_int(&j, "draws", r.draws);
    json_num(&j, "mean_traverse_m", r.mean_traverse_m);
    json_arm(&j, "with_selection", &r.with, trials);
    json_arm(&j, "without_selection", &r.without, trials);
    json_num(&j, "accuracy_gain", gain);
    json_end(&j);
  } else {
    printf("trn experiment: %ld trials, seed %llu; terrain %ld x %ld cells of %g m, k = %g, seed %llu, %zu rocks\n",
           trials, (unsigned long long)seed, size, size, p.cell_m, k, (unsigned long long)p.terrain_seed, r.rocks);
    printf("sensor: %s\n", p.sensor == EXP_SENSOR_PROB ? "local maps sampled from the probability map (eqs. 8-9)"
                                                         : "true DEM + height noise (diagnostic, not the paper's)");
    printf("patch %d cells, window +-%g m, prior error +-%g m, grid %g m, success <= %g m; mean traverse %.2f m\n\n",
           r.patch_cells, window, prior, r.grid_cells * p.cell_m, r.success_radius_m, r.mean_traverse_m);
    printf("%-18s %6s %7s  %8s  %14s   %8s  %s\n", "", "locs", "success", "rate", "95 % CI", "mean err",
           "95 % CI (successes)");
    print_arm("with selection", &r.with);
    print_arm("without selection", &r.without);
    printf("\nsuccessful localizations %.1f %% more accurate with selection (paper: 97.8 %% vs 29.5 %%, 15.3 %%)\n",
           100.0 * gain);
    printf("elapsed %.1f s\n", secs);
  }
  return 0;
}
