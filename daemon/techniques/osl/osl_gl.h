#ifndef SHADEBENCH_OSL_GL_H
#define SHADEBENCH_OSL_GL_H

/* OSL's GL half, shared by its files (osl.c: create, the lighting pass,
 * render and destroy; osl_texgen.c: texture generation; osl_seen.c:
 * visibility "seen"; osl_describe.c: the figures). Render thread only. */

#include <stdbool.h>
#include <stdint.h>

#include "daemon/techniques/osl/osl_atlas.h"
#include "daemon/techniques/osl/osl_info.h"
#include "daemon/techniques/osl/osl_schedule.h"
#include "daemon/techniques/technique.h"

/* The passes of osl_info, in order. */
enum { PASS_LIGHTING, PASS_RASTER };

/* Texels filled around an asset's charts at one level: bilinear filtering
 * reaches one texel past a chart's last centre, and the second covers
 * texels the chart's edge covers only in part. With levels, the raster
 * pass's box filter reaches up to 2 density texels further (a pixel's
 * footprint at the level it reads is under 2 density texels). */
#define OSL_GUTTER_TEXELS(o) ((o)->levels > 1 ? 2 + (int)ceil(2.0 * (o)->density) : 2)

/* The shading atlas: the thesis's 8 bits a channel; asset scenes keep the
 * radiance's range (RGBA16F), since their emissive surfaces, and anything
 * seen through glass blended over it, go past 1 where the other techniques
 * keep it in their HDR output. */
#define OSL_ATLAS_FORMAT(o) ((o)->textured ? GL_RGBA16F : GL_RGBA8)

/* The geometry atlas's channels: position, normal and, in asset scenes,
 * the baked albedo and surface (osl_texgen.frag). */
#define OSL_GEO_CHANNELS 4

/* Atlas memory ceiling; the device's texture size limit applies as well. */
#define OSL_MAX_ATLAS_BYTES (1024.0 * 1024.0 * 1024.0)

struct osl {
    GLuint texgen_prog;
    struct scene_program light, draw;
    GLint work_count_loc, groups_x_loc; /* the lighting pass's per-frame uniforms */
    GLint group_base_loc, group_end_loc;
    /* The geometry atlas: each mesh's object-space position and normal,
     * rasterized in its UV space once per tile size in use (an entry), the
     * entries packed side by side; geo_entry[i] is instance i's. */
    GLuint geo_position, geo_normal;
    /* Asset scenes: the material baked beside them (osl_texgen.frag). */
    bool textured;
    GLuint geo_albedo, geo_surface;
    int geo_w, geo_h, geo_count;
    struct atlas_tile *geo;
    int *geo_entry;
    /* An asset's entries: texels in all, those no triangle covered, and
     * those the gutter filling shaded from a chart's edge. */
    double asset_texels, asset_uncovered, asset_filled;
    GLuint atlas, tile_buffer, work_buffer;
    /* atlas_w x atlas_h is the whole texture; with levels > 1 (resolution
     * "auto") each tile's coarser levels are stacked below level 0's
     * atlas_w x atlas_h0 (osl_level_origin), the same for the geometry
     * atlas (geo_h0), and the raster pass picks each pixel's level from
     * its footprint at density texels a pixel. */
    int atlas_w, atlas_h, atlas_h0, geo_h0;
    int levels;
    double density;
    /* Asset scenes under Phong and Blinn-Phong: the atlas holds diffuse
     * light and atlas_specular the specular, and the raster pass applies
     * the base colour per pixel (osl_light.comp's shade_split). */
    bool split;
    GLuint atlas_specular;
    const struct technique_env *env; /* for the output's depth, read by describe */
    int groups_x_max;
    struct atlas_tile *tiles;
    struct osl_schedule schedule;
    struct osl_work *plan;
    GLuint *work; /* 4 uints per planned object */
    int64_t *rows;
    bool shaded_once;

    /* Figures for timed frames (frame >= 1). */
    int timed_frames;
    double reshaded_sum, texels_sum;
    int reshaded_max;
    double texels_max;
    int initial_objects;
    double initial_texels;
    int frames; /* timed frames of the job */

    /* osl.visibility "seen": the blocks to shade are chosen on the GPU from
     * what the raster pass sampled (osl_select.comp); the figures are
     * counted there and read once, by describe. */
    bool seen;        /* asked for, and lights that move: otherwise the first frame's
                       * shading of every block stays valid, as with whole tiles */
    bool seen_asked;
    bool camera_moves; /* else the first frame's marks stand for every frame */
    bool marked_once;
    struct scene_program draw_mark; /* the raster pass that marks what it reads */
    /* A moving camera: a marking pass of the frame's own camera runs before
     * the selection (draw_mark marks only), so the blocks shaded are the
     * ones this frame reads, at the levels it reads them. */
    bool prepass;
    GLuint select_prog;
    GLint sel_frame_loc, sel_initial_loc, sel_mode_loc, sel_count_loc, sel_count_prev_loc,
        sel_seen_since_loc, sel_margin_loc, sel_blocks_loc, sel_max_groups_loc, light_blocks_x_loc;
    GLint draw_frame_loc;
    int64_t last_frame; /* the last frame rendered, for the last stale check */
    bool last_counted;
    GLuint block_tile_buf, shaded_buf, version_buf, list_buf, stats_buf, marks_tex;
    int blocks_x, blocks_y;
    GLint *versions; /* per instance: the shading its schedule asks for, its light row */
    GLuint stale_blocks;
    double pixels;   /* of the output, for texels per pixel */
    GLint sel_budget_loc;
    int budget_blocks; /* -1: no limit */
    int light_rows;    /* light position rows uploaded a frame: the oldest shading's age + 1 */

    /* osl.change_threshold: per object the frame whose lights its shading
     * is to keep (INT64_MIN: none yet), and what that saved. */
    bool change_on, change_lipschitz;
    const char *change_why; /* when asked for but off */
    int64_t *anchor;
    double change_due, change_saved; /* object due events, and the ones kept, timed frames */
};

/* Sizes of osl_select.comp's Stats: 12 counters, 64 age bins, the keys. */
#define OSL_KEYS 1024
#define OSL_STATS_HEAD 12
#define OSL_STATS_UINTS (OSL_STATS_HEAD + 64 + OSL_KEYS)
/* The oldest shading change detection may keep, in frames beyond the
 * schedule's periods: the light rows the lighting pass can read. */
#define OSL_CHANGE_ROWS 32

/* The "version" of an object's shading nothing reaches: ambient only, the
 * same whenever it was shaded. No due frame equals it (nor the INT_MIN of a
 * block never shaded). */
#define OSL_VERSION_UNLIT INT_MAX

/* Blocks around a seen one that are shaded too: none, since a moving
 * camera marks with its own frame's view before the selection. */
#define OSL_SEEN_MARGIN(o) 0

/* Where level l of an atlas whose level 0 is w x h0 begins: level 0 at the
 * origin, the others side by side below it (level 1 at (0, h0), level 2 at
 * (w/2, h0), level 3 at (3w/4, h0), ...), so the whole takes w x 3h0/2 and
 * a tile at (x, y) of size s has its level l at origin + (x, y) >> l, of
 * size s >> l (tiles are aligned to their size). osl_light.comp and
 * osl_draw.frag compute the same. */
static inline void osl_level_origin(int l, int w, int h0, int *x, int *y)
{
    *x = l == 0 ? 0 : w - (w >> (l - 1));
    *y = l == 0 ? 0 : h0;
}

/* The levels of a tile of the given size: down to 8 texels (one block). */
static inline int osl_tile_levels(int size, int levels)
{
    int n = 1;
    while (n < levels && (size >> n) >= 8)
        n++;
    return n;
}

/* The figures for the result (osl_describe.c). */
json_t *osl_describe(void *state);

/* The raster pass's uniforms that never change: the atlas's unit, its
 * sizes and the density its levels are picked by (osl.c). */
void osl_set_draw_uniforms(const struct osl *o, GLuint prog);

/* The lighting pass's program and inputs (osl.c). */
void osl_bind_light_inputs(const struct osl *o, const struct technique_env *env);

/* Texture generation: the geometry atlas (osl_texgen.c). */
bool osl_generate_textures(struct osl *o, const struct technique_env *env, char *err,
                           size_t errlen);

/* osl.visibility "seen" (osl_seen.c). */
bool osl_seen_create(struct osl *o, const struct technique_env *env, char *err, size_t errlen);
void osl_seen_bind(const struct osl *o);
void osl_seen_light_pass(struct osl *o, const struct technique_env *env, int64_t frame,
                         bool initial, bool count);
/* Objects read, reshaded, and reshaded unread (out); the blocks the last
 * frame read at each level (read_by_level). */
void osl_seen_objects(const struct osl *o, int out[3], long read_by_level[16]);
/* Counts the reads of frame - 1 (stale, unshaded, their age) when that
 * was a timed frame rendered just before, from the marks it left: before
 * a marking pass overwrites them, and once after the last frame. */
void osl_seen_count_reads(struct osl *o, int64_t frame);

#endif
