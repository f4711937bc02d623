/* OSL's figures for the result (osl_gl.h). */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/gpu/glutil.h"
#include "common/log.h"
#include "daemon/gpu/bindings.h"
#include "daemon/techniques/osl/osl_gl.h"

/* The smallest age a fraction q of the counted reads is at or under. */
static int age_quantile(const GLuint *age, double q)
{
    double total = 0, sum = 0;
    for (int a = 0; a < 64; a++)
        total += age[a];
    if (total <= 0)
        return 0;
    for (int a = 0; a < 64; a++) {
        sum += age[a];
        if (age[a] && sum >= q * total)
            return a;
    }
    return 63;
}

/* Pixels the objects cover in the last frame (its depth below the far
 * plane), for texels per covered pixel; -1 with MSAA (a multisampled depth
 * is not read back). Outside the timed frames. */
static double covered_pixels(const struct osl *o)
{
    const struct technique_env *env = o->env;
    if (env->samples > 1)
        return -1;
    size_t n = (size_t)env->width * env->height;
    float *depth = malloc(n * sizeof(float));
    if (!depth)
        return -1;
    glBindTexture(GL_TEXTURE_2D, env->output_depth);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glGetTexImage(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glBindTexture(GL_TEXTURE_2D, 0);
    double covered = 0;
    for (size_t i = 0; i < n; i++)
        covered += depth[i] < 1.0f;
    free(depth);
    return covered;
}

json_t *osl_describe(void *state)
{
    struct osl *o = state;
    int n = o->schedule.count;
    json_t *tiles = json_object(), *periods = json_object();
    double tile_texels = 0;
    for (int i = 0; i < n; i++) {
        char key[16];
        snprintf(key, sizeof(key), "%d", o->tiles[i].size);
        json_t *c = json_object_get(tiles, key);
        json_object_set_new(tiles, key, json_integer(c ? json_integer_value(c) + 1 : 1));
        snprintf(key, sizeof(key), "%d", o->schedule.period[i]);
        c = json_object_get(periods, key);
        json_object_set_new(periods, key, json_integer(c ? json_integer_value(c) + 1 : 1));
        tile_texels += (double)o->tiles[i].size * o->tiles[i].size;
    }
    double frames = o->timed_frames ? o->timed_frames : 1;
    GLuint stats[OSL_STATS_HEAD + 64] = {0};
    int objects[3] = {-1, -1, -1};
    long read_by_level[16] = {0};
    if (o->seen) {
        /* Counted on the GPU over the timed frames; read once, here, after
         * checking the last frame's reads (the next frame would have). */
        osl_seen_count_reads(o, o->last_frame + 1);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, o->stats_buf);
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof(stats), stats);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        o->texels_sum = 64.0 * stats[4];
        o->texels_max = 64.0 * stats[5];
        o->stale_blocks = stats[6];
        osl_seen_objects(o, objects, read_by_level);
    }
    double texgen_bytes = 2.0 * 16.0 * o->geo_w * o->geo_h;
    json_t *d = json_pack(
        "{s:{s:f, s:i}, s:{s:f, s:f, s:f}, s:{s:i, s:i, s:f, s:f, s:f}, s:o, s:o, s:{s:i, s:f}, s:f}",
        "objects_reshaded_per_frame", "mean", o->reshaded_sum / frames, "max", o->reshaded_max,
        "texels_shaded_per_frame", "mean", o->texels_sum / frames, "max", o->texels_max,
        "total", o->texels_sum,
        "atlas", "width", o->atlas_w, "height", o->atlas_h, "texels",
        (double)o->atlas_w * o->atlas_h, "bytes",
        (double)o->atlas_w * o->atlas_h * (o->textured ? 8.0 : 4.0),
        "tile_texels", tile_texels,
        "tiles_by_size", tiles, "objects_by_period", periods,
        "initial_shading", "objects", o->initial_objects, "texels", o->initial_texels,
        "texgen_bytes", texgen_bytes);
    if (d && o->levels > 1)
        json_object_set_new(d, "levels",
                            json_pack("{s:i, s:f, s:s}", "count", o->levels, "texel_density",
                                      o->density, "rule",
                                      "each pixel reads the finest level with texel_density to "
                                      "twice that texels a pixel along each axis (by area), no "
                                      "coarser than leaves its chart 4 texels across"));
    if (d && o->asset_texels > 0)
        json_object_set_new(d, "asset_charts",
                            json_pack("{s:f, s:f, s:f, s:i}", "texels", o->asset_texels,
                                      "uncovered_share", o->asset_uncovered / o->asset_texels,
                                      "gutter_filled_share", o->asset_filled / o->asset_texels,
                                      "gutter_texels", OSL_GUTTER_TEXELS(o)));
    if (o->seen_asked && !o->seen && d)
        json_object_set_new(d, "visibility",
                            json_pack("{s:s, s:b, s:s}", "mode", "seen", "active", 0, "why",
                                      "the lights stand still: the first frame shades every "
                                      "block once, and that shading stays what the schedule "
                                      "asks for"));
    if (o->seen && d) {
        /* Objects are not reshaded whole: only the texels are counted. */
        json_object_del(d, "objects_reshaded_per_frame");
        json_object_del(d, "initial_shading");
        json_object_set_new(d, "visibility",
                            json_pack("{s:s, s:b, s:b, s:f, s:I, s:I, s:i, s:i}", "mode", "seen",
                                      "active", 1, "camera_moves", o->camera_moves,
                                      "texels_per_pixel",
                                      o->pixels > 0 ? o->texels_sum / frames / o->pixels : 0.0,
                                      "stale_blocks", (json_int_t)o->stale_blocks,
                                      "blocks", (json_int_t)o->blocks_x * o->blocks_y,
                                      "margin_blocks", OSL_SEEN_MARGIN(o), "block_texels", 64));
        json_t *vis = json_object_get(d, "visibility");
        double covered = covered_pixels(o);
        if (covered > 0) {
            json_object_set_new(vis, "covered_pixels", json_real(covered));
            json_object_set_new(vis, "texels_per_covered_pixel",
                                json_real(o->texels_sum / frames / covered));
        }
        json_t *levels = json_array();
        for (int l = 0; l < o->levels; l++)
            json_array_append_new(levels, json_integer(read_by_level[l]));
        json_object_set_new(vis, "blocks_read_by_level", levels);
        if (objects[0] >= 0) {
            json_object_set_new(vis, "objects_read", json_integer(objects[0]));
            json_object_set_new(vis, "objects_reshaded", json_integer(objects[1]));
            json_object_set_new(vis, "unread_objects_reshaded", json_integer(objects[2]));
        }
        /* Frames since the lights of each read block's shading, over the
         * blocks the timed frames read. */
        const GLuint *age = stats + OSL_STATS_HEAD;
        json_int_t reads = 0;
        for (int k = 0; k < 64; k++)
            reads += age[k];
        json_object_set_new(d, "staleness",
                            json_pack("{s:I, s:i, s:i, s:i, s:I, s:s}", "reads", reads,
                                      "median", age_quantile(age, 0.5),
                                      "p95", age_quantile(age, 0.95), "max",
                                      age_quantile(age, 1.0), "unshaded_reads",
                                      (json_int_t)stats[10], "unit",
                                      "frames since the lights of the shading read (63: 63 "
                                      "or more)"));
        json_object_set_new(d, "budget",
                            o->budget_blocks < 0
                                ? json_pack("{s:b}", "active", 0)
                                : json_pack("{s:b, s:i, s:i, s:I, s:f}", "active", 1,
                                            "texels", o->budget_blocks * 64, "blocks",
                                            o->budget_blocks, "overflow_frames",
                                            (json_int_t)stats[8], "deferred_blocks_per_frame",
                                            stats[9] / frames));
    }
    if (o->seen && o->change_on)
        json_object_set_new(d, "change",
                            json_pack("{s:b, s:s, s:f, s:f}", "active", 1, "bound",
                                      o->change_lipschitz ? "phong motion" : "range",
                                      "reshades_due_per_frame", o->change_due / frames,
                                      "reshades_saved_per_frame", o->change_saved / frames));
    else if (o->change_why)
        json_object_set_new(d, "change",
                            json_pack("{s:b, s:s}", "active", 0, "why", o->change_why));
    return d;
}
