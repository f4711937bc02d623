/* A sweep's table as CSV (table.csv of shadebench sweep --out and of a
 * gathered fleet sweep): one row per point, the swept values, then the
 * figures. Single-threaded. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <string.h>

#include "client/fleet.h"
#include "common/result_keys.h"

static void csv_cell(FILE *f, const json_t *v)
{
    if (json_is_number(v))
        fprintf(f, "%.10g", json_number_value(v));
    else if (json_is_string(v)) {
        /* RFC 4180: quoted, inner quotes doubled (renderer strings may hold any). */
        fputc('"', f);
        for (const char *c = json_string_value(v); *c; c++) {
            if (*c == '"')
                fputc('"', f);
            fputc(*c, f);
        }
        fputc('"', f);
    } else if (json_is_boolean(v))
        fputs(json_is_true(v) ? "true" : "false", f);
}

/* One row per point: the swept values, then the figures. */
bool sweep_csv_write(const json_t *sweep, const char *path)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return false;
    json_t *points = json_object_get(sweep, "points");
    json_t *keys = json_array(); /* swept fields, in order of first appearance */
    size_t i, k;
    json_t *row, *key;
    json_array_foreach(points, i, row) {
        const char *name;
        json_t *v;
        json_object_foreach(json_object_get(row, "values"), name, v) {
            bool seen = false;
            json_array_foreach(keys, k, key) seen = seen || !strcmp(json_string_value(key), name);
            if (!seen)
                json_array_append_new(keys, json_string(name));
        }
    }
    /* A fleet's table: which device class, node and GPU measured each row. */
    bool devices = false;
    json_array_foreach(points, i, row) devices = devices || json_object_get(row, "device");
    if (devices)
        fprintf(f, "device,node,gl_renderer,");
    json_array_foreach(keys, k, key) fprintf(f, "%s,", json_string_value(key));
    static const char *const series[] = {RK_FRAME_MS, RK_GPU_MS, RK_CPU_MS};
    fprintf(f, "technique,job,status");
    for (int s = 0; s < 3; s++)
        fprintf(f, ",%s_median,%s_ci95_low,%s_ci95_high,%s_over", series[s], series[s], series[s],
                series[s]);
    fprintf(f, ",worst_ssim,worst_ssim_min,worst_flip,pdiff_failed_captures,criterion_holds\n");
    json_array_foreach(points, i, row) {
        json_t *values = json_object_get(row, "values");
        json_t *device = json_object_get(row, "device");
        static const char *const dev_keys[] = {"class", "node", "gl_renderer"};
        for (int d = 0; devices && d < 3; d++) {
            csv_cell(f, json_object_get(device, dev_keys[d]));
            fputc(',', f);
        }
        json_array_foreach(keys, k, key) {
            csv_cell(f, json_object_get(values, json_string_value(key)));
            fputc(',', f);
        }
        csv_cell(f, json_object_get(row, "technique"));
        fputc(',', f);
        csv_cell(f, json_object_get(row, "job"));
        fputc(',', f);
        csv_cell(f, json_object_get(row, "status"));
        for (int s = 0; s < 3; s++) {
            json_t *cell = json_object_get(row, series[s]);
            json_t *ci = json_object_get(cell, RK_CI95);
            fputc(',', f);
            csv_cell(f, json_object_get(cell, RK_MEDIAN));
            fputc(',', f);
            csv_cell(f, json_array_get(ci, 0));
            fputc(',', f);
            csv_cell(f, json_array_get(ci, 1));
            fputc(',', f);
            csv_cell(f, json_object_get(cell, "over"));
        }
        static const char *const tail[] = {RK_WORST_SSIM, RK_WORST_SSIM_MIN, RK_WORST_FLIP,
                                           RK_PDIFF_FAILED_CAPTURES, "criterion_holds"};
        for (size_t t = 0; t < sizeof(tail) / sizeof(tail[0]); t++) {
            fputc(',', f);
            csv_cell(f, json_object_get(row, tail[t]));
        }
        fputc('\n', f);
    }
    json_decref(keys);
    return fclose(f) == 0;
}

