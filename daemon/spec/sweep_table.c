/* Sweep tables (GL-free): a point's row from its finished job, and a grid's
 * result over its table. The daemon's sweeps and the client's gathering of
 * a fleet's task folders both build their tables here, so that a sweep run
 * by one daemon and the same sweep run across a Slurm array give the same
 * rows. Any thread (pure functions of their arguments). */
#define _POSIX_C_SOURCE 200809L
#include "daemon/spec/sweep_table.h"

#include <stdlib.h>
#include <string.h>

#include "common/result_keys.h"
#include "common/stats.h"

json_t *sweep_table_row(const json_t *job, json_t *values)
{
    json_t *r = json_object_get(job, RK_RESULT);
    json_t *spec = json_object_get(job, "spec");
    json_t *row = json_pack("{s:o, s:s, s:s, s:O}", "values", values, "job",
                            json_string_value(json_object_get(job, "id")), "status",
                            json_string_value(json_object_get(job, "status")), "technique",
                            json_object_get(spec, "technique"));
    if (json_object_get(job, "error"))
        json_object_set(row, "error", json_object_get(job, "error"));
    if (!r)
        return row;
    json_t *rep = json_object_get(r, RK_REPEAT);
    static const char *const series[] = {RK_FRAME_MS, RK_GPU_MS, RK_CPU_MS};
    for (int k = 0; k < 3; k++) {
        json_t *st = json_object_get(r, series[k]);
        json_t *across = rep ? json_object_get(rep, series[k]) : NULL;
        /* Repeated jobs: the mean of run medians and its interval; single runs:
         * the median and its distribution-free interval. */
        json_t *cell =
            across ? json_pack("{s:O, s:O, s:s}", RK_MEDIAN, json_object_get(across, RK_MEAN), RK_CI95,
                               json_object_get(across, RK_CI95), "over", "runs")
                   : json_pack("{s:O, s:O, s:s}", RK_MEDIAN, json_object_get(st, RK_MEDIAN), RK_CI95,
                               json_object_get(st, RK_MEDIAN_CI95), "over", "frames");
        /* The distribution of the (first run's) frames, for the charts. */
        static const char *const keep[] = {RK_MIN, RK_P5, RK_P95, RK_P99, RK_MAX};
        for (int i = 0; i < 5; i++)
            json_object_set(cell, keep[i], json_object_get(st, keep[i]));
        json_object_set_new(row, series[k], cell);
    }
    if (rep)
        json_object_set(row, RK_STABLE, json_object_get(rep, RK_STABLE));
    /* A point timed in slices (accept_sliced_timing) says so, and its
     * timing cells too, so that no chart or verdict reads it beside whole
     * frames unmarked (sweep_table_result names the mix). */
    if (json_is_true(json_object_get(r, "sliced"))) {
        json_object_set_new(row, "sliced", json_true());
        for (int k = 0; k < 3; k++)
            json_object_set_new(json_object_get(row, series[k]), "sliced", json_true());
    }
    /* Execution time of the timed frames, over runs: what the thesis tabled. */
    json_t *runs = json_object_get(r, RK_RUNS);
    size_t nruns = runs ? json_array_size(runs) : 1;
    double *walls = malloc(nruns * sizeof(double));
    if (walls) {
        for (size_t i = 0; i < nruns; i++)
            walls[i] = json_number_value(json_object_get(runs ? json_array_get(runs, i) : r, RK_WALL_S));
        struct stats st;
        stats_compute(walls, nruns, &st);
        json_object_set_new(row, RK_WALL_S, json_pack("{s:I, s:f, s:f, s:f}", RK_RUNS, (json_int_t)nruns,
                                                     RK_MEAN, st.mean, RK_MEDIAN, st.median, RK_STDDEV,
                                                     st.stddev));
        free(walls);
    }
    json_t *q = json_object_get(r, RK_QUALITY);
    if (q) {
        json_object_set(row, RK_WORST_SSIM, json_object_get(json_object_get(q, RK_WORST_SSIM), "value"));
        json_object_set(row, RK_WORST_SSIM_MIN, json_object_get(json_object_get(q, RK_WORST_SSIM_MIN), "value"));
        json_object_set(row, RK_WORST_FLIP, json_object_get(json_object_get(q, RK_WORST_FLIP), "mean"));
        json_object_set(row, RK_PDIFF_FAILED_CAPTURES, json_object_get(q, RK_PDIFF_FAILED_CAPTURES));
        json_t *flicker = json_object_get(json_object_get(q, RK_WORST_FLICKER), "value");
        if (flicker) /* temporal.frames: the flicker_max criterion's figure */
            json_object_set(row, RK_WORST_FLICKER, flicker);
    }
    /* Post hook: the worst capture's non-finite pixels, for breaking points. */
    json_t *nonfinite = json_object_get(r, RK_NONFINITE);
    if (nonfinite)
        json_object_set(row, "nonfinite_pixels", json_object_get(nonfinite, RK_PIXELS_MAX));
    /* Bounded light lists and the shadow atlas: where they overflow. */
    json_int_t lists, shadows;
    sweep_overflow_frames(r, &lists, &shadows);
    if (lists >= 0)
        json_object_set_new(row, "light_overflow_frames", json_integer(lists));
    if (shadows >= 0)
        json_object_set_new(row, "shadow_drop_frames", json_integer(shadows));
    return row;
}

/* With one numeric parameter, the question the thesis answered by hand:
 * the largest value whose captures all pass PerceptualDiff. Over the whole
 * table, so that a resumed sweep counts the points run before the stop. */
json_t *sweep_table_result(const struct sweep_spec *spec, const json_t *points)
{
    json_t *passing = json_array(), *best = NULL, *row;
    size_t i;
    json_array_foreach(points, i, row) {
        json_t *failed = json_object_get(row, RK_PDIFF_FAILED_CAPTURES);
        if (json_is_integer(failed) && json_integer_value(failed) == 0)
            json_array_append(passing, json_object_get(row, "values"));
    }
    json_t *res = json_pack("{s:o}", "pdiff_passing", passing);
    /* Timing rules: a table that mixes points timed in slices with points
     * timed whole says so, with the sliced points' values. */
    json_t *sliced = json_array();
    size_t timed = 0;
    json_array_foreach(points, i, row) {
        if (json_object_get(row, RK_FRAME_MS))
            timed++;
        if (json_is_true(json_object_get(row, "sliced")))
            json_array_append(sliced, json_object_get(row, "values"));
    }
    if (json_array_size(sliced) > 0)
        json_object_set_new(res, "timing_rules",
                            json_pack("{s:s, s:o}", "warning",
                                      json_array_size(sliced) < timed
                                          ? "some points were timed in slices "
                                            "(accept_sliced_timing) and others whole: their "
                                            "times do not compare"
                                          : "every point was timed in slices "
                                            "(accept_sliced_timing)",
                                      "sliced_points", sliced));
    else
        json_decref(sliced);
    if (spec->nparams == 1) {
        json_t *values;
        json_array_foreach(passing, i, values) {
            json_t *v = json_object_get(values, spec->params[0]);
            if (json_is_number(v) && (!best || json_number_value(v) > json_number_value(best)))
                best = v;
        }
        json_object_set_new(res, "largest_pdiff_pass",
                            json_pack("{s:s, s:O}", "param", spec->params[0], "value",
                                      best ? best : json_null()));
    }
    return res;
}
