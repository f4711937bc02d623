#include "daemon/spec/job_figures.h"

#include "common/result_keys.h"

/* A series' headline: over the runs of a repeated job (the median of run
 * medians, with the across-run interval), else over the frames. */
static json_t *series_figure(const json_t *result, const char *series)
{
    json_t *across = json_object_get(json_object_get(result, RK_REPEAT), series);
    json_t *st = json_object_get(result, series);
    if (!st && !across)
        return NULL;
    if (across)
        return json_pack("{s:O, s:O, s:s}", RK_MEDIAN, json_object_get(across, RK_MEDIAN), RK_CI95,
                         json_object_get(across, RK_CI95), "over", "runs");
    return json_pack("{s:O, s:O, s:s}", RK_MEDIAN, json_object_get(st, RK_MEDIAN), RK_CI95,
                     json_object_get(st, RK_MEDIAN_CI95), "over", "frames");
}

json_t *job_figures(const json_t *result)
{
    if (!json_is_object(result))
        return NULL;
    json_t *o = json_object();
    static const char *const series[] = {RK_FRAME_MS, RK_GPU_MS, RK_CPU_MS};
    for (int k = 0; k < 3; k++) {
        json_t *fig = series_figure(result, series[k]);
        if (fig)
            json_object_set_new(o, series[k], fig);
    }
    json_t *rep = json_object_get(result, RK_REPEAT);
    json_object_set_new(o, RK_RUNS, json_integer(rep ? json_integer_value(json_object_get(rep, RK_RUNS)) : 1));
    json_t *ssim = json_object_get(json_object_get(json_object_get(result, RK_QUALITY), RK_WORST_SSIM),
                                   "value");
    if (json_is_number(ssim))
        json_object_set(o, RK_WORST_SSIM, ssim);
    /* Timed in slices (accept_sliced_timing): never read as whole frames. */
    if (json_is_true(json_object_get(result, "sliced")))
        json_object_set_new(o, "sliced", json_true());
    json_t *dev = json_object_get(result, "device");
    static const char *const keep[] = {"gl_renderer", "gl_version"};
    for (int k = 0; k < 2; k++)
        if (json_is_string(json_object_get(dev, keep[k])))
            json_object_set(o, keep[k], json_object_get(dev, keep[k]));
    return o;
}
