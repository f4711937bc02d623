/* Object Space Lighting (thesis OSLProg, chapters 2.1.1 and 3.1.2):
 *  1. texture generation: each model rasterized in UV space into object-space
 *     position and normal textures (once per model and tile size);
 *  2. lighting: a compute pass shades the texels of the objects due this
 *     frame into one shared atlas, one tile per instance;
 *  3. rasterization: every object drawn sampling its tile.
 * Beyond the thesis: osl.resolution "auto" sizes each tile from the object's
 * size on screen, osl.reshade "touched" reshades only objects a moving
 * light reaches (see osl_schedule.h), and osl.visibility "seen" shades only
 * the atlas blocks the raster pass sampled (osl_select.comp), within
 * osl.budget_texels a frame, and with osl.change_threshold only when the
 * lights moved enough to matter (osl_change_bound). */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/gpu/glutil.h"
#include "common/log.h"
#include "daemon/gpu/bindings.h"
#include "daemon/techniques/osl/osl_atlas.h"
#include "daemon/techniques/osl/osl_info.h"
#include "daemon/techniques/osl/osl_schedule.h"
#include "daemon/techniques/technique.h"

/* The passes of osl_info, in order. */
enum { PASS_LIGHTING, PASS_RASTER };

/* Texels filled around an asset's charts: bilinear filtering reaches one
 * texel past a chart's last centre, and the second covers the raster pass's
 * seen-margin of moving cameras at the smallest tiles. */
#define OSL_GUTTER_TEXELS 2

/* The shading atlas: the thesis's 8 bits a channel; asset scenes keep the
 * radiance's range (RGBA16F), since their emissive surfaces, and anything
 * seen through glass blended over it, go past 1 where the other techniques
 * keep it in their HDR output. */
#define OSL_ATLAS_FORMAT(o) ((o)->textured ? GL_RGBA16F : GL_RGBA8)

/* The geometry atlas's channels: position, normal and, in asset scenes,
 * the baked albedo and surface (osl_texgen.frag). */
#define OSL_GEO_CHANNELS 4

/* Atlas memory ceiling; the device's texture size limit applies as well. */
static const double OSL_MAX_ATLAS_BYTES = 1024.0 * 1024.0 * 1024.0;

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
    int atlas_w, atlas_h;
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

/* Blocks around a seen one that are shaded too, for a camera that moves. */
#define OSL_SEEN_MARGIN(o) ((o)->camera_moves ? 1 : 0)

static bool check_limits(struct osl *o, const struct technique_env *env, int *max_tex,
                         char *err, size_t errlen)
{
    GLint size[2], count[2], invocations = 0, images = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, max_tex);
    glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_SIZE, 0, &size[0]);
    glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_SIZE, 1, &size[1]);
    glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 0, &count[0]);
    glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 1, &count[1]);
    glGetIntegerv(GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS, &invocations);
    glGetIntegerv(GL_MAX_COMPUTE_IMAGE_UNIFORMS, &images);
    if (size[0] < 8 || size[1] < 8 || invocations < 64 || images < 1) {
        snprintf(err, errlen, "osl: the compute limits of this device (work group "
                 "%dx%d, %d invocations, %d images) are below the 8x8 groups and one "
                 "image the lighting pass needs", size[0], size[1], invocations, images);
        return false;
    }
    const struct osl_options *opt = env->options;
    int largest = opt->resolution ? opt->resolution : OSL_TILE_MAX;
    if (largest > *max_tex) {
        snprintf(err, errlen, "osl.resolution %d exceeds GL_MAX_TEXTURE_SIZE %d",
                 largest, *max_tex);
        return false;
    }
    o->groups_x_max = count[0];
    /* Worst case: every object shaded in one dispatch. */
    double blocks = 0;
    for (int i = 0; i < o->schedule.count; i++)
        blocks += (double)(o->tiles[i].size / 8) * (o->tiles[i].size / 8);
    if (blocks > (double)count[0] * count[1]) {
        snprintf(err, errlen, "osl: %.0f work groups exceed this device's compute "
                 "limit of %dx%d", blocks, count[0], count[1]);
        return false;
    }
    return true;
}

static bool choose_tiles(struct osl *o, const struct technique_env *env, int max_tex,
                         char *err, size_t errlen)
{
    const struct scene *s = env->scene;
    int n = s->instance_count;
    int *sizes = malloc((size_t)n * sizeof(int));
    if (!sizes) {
        snprintf(err, errlen, "out of memory");
        return false;
    }
    const struct osl_options *opt = env->options;
    /* 0: one texel a pixel, or two under PBR: at one, bilinear filtering
     * flattens GGX's narrow highlights (SSIM against forward 0.987 at one,
     * 0.9965 at two, 0.9993 at four: the lights preset, 160x120). */
    double density = opt->texel_density;
    if (density == 0)
        density = env->defines && strstr(env->defines, "LIGHTING_PBR") ? 2.0 : 1.0;
    for (int i = 0; i < n; i++) {
        if (opt->resolution) {
            sizes[i] = opt->resolution;
            continue;
        }
        double ppu = scene_projected_diameter(s, i) / (2.0 * scene_instance_bound(s, i));
        const struct mesh *m = &s->meshes[s->instances[i].mesh];
        sizes[i] = osl_auto_tile_size(ppu, m->uv_per_unit / s->instances[i].scale, density);
    }
    /* The packer counts 4 bytes a texel; an HDR atlas takes 8. */
    bool ok = osl_atlas_pack(sizes, n, max_tex, OSL_MAX_ATLAS_BYTES / (o->textured ? 2.0 : 1.0),
                             o->tiles, &o->atlas_w,
                             &o->atlas_h, err, errlen);
    free(sizes);
    return ok;
}

/* The geometry entries: one per (mesh, tile size) in use, in mesh order
 * then size order, so the same scene always packs the same way. */
static bool plan_geometry(struct osl *o, const struct scene *s, int **sizes_out, int **mesh_out)
{
    int n = s->instance_count;
    int *sizes = malloc((size_t)(n ? n : 1) * sizeof(int));
    int *mesh = malloc((size_t)(n ? n : 1) * sizeof(int));
    o->geo_entry = malloc((size_t)(n ? n : 1) * sizeof(int));
    if (!sizes || !mesh || !o->geo_entry) {
        free(sizes);
        free(mesh);
        return false;
    }
    int count = 0;
    for (int m = 0; m < s->mesh_count; m++)
        for (int size = OSL_TILE_MAX; size >= 1; size >>= 1) {
            int entry = -1;
            for (int i = 0; i < n; i++) {
                if (s->instances[i].mesh != m || o->tiles[i].size != size)
                    continue;
                if (entry < 0) {
                    entry = count++;
                    sizes[entry] = size;
                    mesh[entry] = m;
                }
                o->geo_entry[i] = entry;
            }
        }
    o->geo_count = count;
    *sizes_out = sizes;
    *mesh_out = mesh;
    return true;
}

/* An asset's uv1 charts are not whole rectangles (the procedural meshes'
 * are, and the raster pass clamps to them): texels around each chart are
 * filled from the chart's edge, so that bilinear filtering across the edge
 * reads about the same surface. Counts what no triangle covered. */
static bool dilate_entry(struct osl *o, const GLuint *scratch, int channels, int size)
{
    size_t texels = (size_t)size * size;
    float *img[OSL_GEO_CHANNELS] = {NULL};
    bool ok = true;
    for (int c = 0; c < channels; c++)
        ok = ok && (img[c] = malloc(texels * 4 * sizeof(float)));
    if (ok) {
        glPixelStorei(GL_PACK_ALIGNMENT, 4);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        for (int c = 0; c < channels; c++) {
            glBindTexture(GL_TEXTURE_2D, scratch[c]);
            glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_FLOAT, img[c]);
        }
        size_t covered = 0;
        for (size_t t = 0; t < texels; t++)
            covered += img[0][t * 4 + 3] > 0.0f;
        o->asset_texels += (double)texels;
        o->asset_uncovered += (double)(texels - covered);
        o->asset_filled += (double)osl_dilate_geometry(img[0], img[1], img + 2, channels - 2, size,
                                                       OSL_GUTTER_TEXELS);
        for (int c = 0; c < channels; c++) {
            glBindTexture(GL_TEXTURE_2D, scratch[c]);
            glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, size, size, GL_RGBA, GL_FLOAT, img[c]);
        }
    }
    for (int c = 0; c < channels; c++)
        free(img[c]);
    return ok;
}

/* Texture generation: each entry rasterized alone into a scratch target of
 * its size at the origin, then copied into its place in the geometry
 * atlas. Rendering at the origin keeps every texel the exact sample it was
 * when each mesh had textures of its own (a viewport offset into a larger
 * target would round window coordinates differently). Asset scenes bake
 * their materials into two more channels, each entry with its mesh's
 * material bound. */
static bool generate_textures(struct osl *o, const struct technique_env *env, char *err,
                              size_t errlen)
{
    const struct scene *s = env->scene;
    int *sizes = NULL, *mesh = NULL;
    if (!plan_geometry(o, s, &sizes, &mesh)) {
        snprintf(err, errlen, "osl: out of memory");
        return false;
    }
    int channels = o->textured ? 4 : 2;
    o->geo = calloc((size_t)(o->geo_count ? o->geo_count : 1), sizeof(*o->geo));
    GLint max_tex = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_tex);
    /* 16 bytes a channel's texel (RGBA32F), against the packer's 4. */
    bool ok = o->geo && osl_atlas_pack(sizes, o->geo_count, max_tex,
                                       1024.0 * 1024.0 * 1024.0 / (4.0 * channels), o->geo,
                                       &o->geo_w, &o->geo_h, err, errlen);
    if (!ok) {
        if (!o->geo)
            snprintf(err, errlen, "osl: out of memory");
        free(sizes);
        free(mesh);
        return false;
    }
    GLuint texs[OSL_GEO_CHANNELS] = {0}, scratch[OSL_GEO_CHANNELS] = {0}, fbo;
    glGenTextures(channels, texs);
    o->geo_position = texs[0];
    o->geo_normal = texs[1];
    o->geo_albedo = texs[2];
    o->geo_surface = texs[3];
    for (int t = 0; t < channels; t++) {
        glBindTexture(GL_TEXTURE_2D, texs[t]);
        glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA32F, o->geo_w, o->geo_h);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    }
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    struct scene_program texgen = gpu_scene_program(env->gpu, o->texgen_prog);
    gpu_scene_bind(env->gpu, &texgen);
    static const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1,
                                  GL_COLOR_ATTACHMENT2, GL_COLOR_ATTACHMENT3};
    glDrawBuffers(channels, bufs);
    int scratch_size = 0;
    for (int e = 0; e < o->geo_count && ok; e++) {
        int size = sizes[e], m = mesh[e];
        if (size != scratch_size) {
            glDeleteTextures(channels, scratch);
            glGenTextures(channels, scratch);
            for (int t = 0; t < channels; t++) {
                glBindTexture(GL_TEXTURE_2D, scratch[t]);
                glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA32F, size, size);
            }
            scratch_size = size;
        }
        for (int t = 0; t < channels; t++)
            glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + (GLenum)t, GL_TEXTURE_2D,
                                   scratch[t], 0);
        ok = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
        if (!ok) {
            snprintf(err, errlen, "osl: texture generation framebuffer incomplete");
            break;
        }
        glViewport(0, 0, size, size);
        glClearColor(0, 0, 0, 0);
        glClear(GL_COLOR_BUFFER_BIT);
        if (o->textured)
            gpu_scene_bind_material(env->gpu, m, SB_LOC_MATERIAL);
        glBindVertexArray(env->gpu->vao[m]);
        glDrawElements(GL_TRIANGLES, (GLsizei)s->meshes[m].index_count, GL_UNSIGNED_INT, NULL);
        if (m >= SCENE_MESH_PROCEDURAL && !dilate_entry(o, scratch, channels, size)) {
            snprintf(err, errlen, "osl: out of memory filling gutters");
            ok = false;
            break;
        }
        for (int t = 0; t < channels; t++)
            glCopyImageSubData(scratch[t], GL_TEXTURE_2D, 0, 0, 0, 0, texs[t], GL_TEXTURE_2D, 0,
                               o->geo[e].x, o->geo[e].y, 0, size, size, 1);
    }
    glDeleteTextures(channels, scratch);
    glBindVertexArray(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &fbo);
    free(sizes);
    free(mesh);
    return ok;
}

/* The lighting pass's program and inputs, whichever way it finds its blocks:
 * the tiles, the atlas to write, each mesh's position and normal textures. */
static void bind_light_inputs(const struct osl *o, const struct technique_env *env)
{
    gpu_scene_bind(env->gpu, &o->light);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_OSL_TILES, o->tile_buffer);
    glBindImageTexture(SB_IMG_OSL_ATLAS, o->atlas, 0, GL_FALSE, 0, GL_WRITE_ONLY,
                       OSL_ATLAS_FORMAT(o));
    glActiveTexture(GL_TEXTURE0 + SB_TEX_OSL_GEO_POSITION);
    glBindTexture(GL_TEXTURE_2D, o->geo_position);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_OSL_GEO_NORMAL);
    glBindTexture(GL_TEXTURE_2D, o->geo_normal);
    if (o->textured) {
        glActiveTexture(GL_TEXTURE0 + SB_TEX_OSL_GEO_ALBEDO);
        glBindTexture(GL_TEXTURE_2D, o->geo_albedo);
        glActiveTexture(GL_TEXTURE0 + SB_TEX_OSL_GEO_SURFACE);
        glBindTexture(GL_TEXTURE_2D, o->geo_surface);
    }
    glActiveTexture(GL_TEXTURE0);
}

static GLuint ssbo(GLsizeiptr bytes, const void *data, GLenum usage)
{
    GLuint b;
    glGenBuffers(1, &b);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, b);
    glBufferData(GL_SHADER_STORAGE_BUFFER, bytes, data, usage);
    return b;
}

/* osl.visibility "seen": per atlas block its instance and the shading it
 * holds (none yet), per instance its scheduled shading, the block list and
 * counters, the marks image, and the selection program. */
static bool seen_create(struct osl *o, const struct technique_env *env, char *err, size_t errlen)
{
    const struct scene *s = env->scene;
    int n = s->instance_count;
    o->blocks_x = o->atlas_w / 8;
    o->blocks_y = o->atlas_h / 8;
    size_t blocks = (size_t)o->blocks_x * (size_t)o->blocks_y;
    GLuint *owner = malloc(blocks * sizeof(GLuint));
    GLint *never = malloc(blocks * 8 * sizeof(GLint));
    GLuint *zero = calloc(OSL_STATS_UINTS, sizeof(GLuint));
    o->versions = calloc((size_t)n * 2, sizeof(GLint));
    if (!owner || !never || !zero || !o->versions) {
        free(owner);
        free(never);
        free(zero);
        snprintf(err, errlen, "osl: out of memory");
        return false;
    }
    for (size_t b = 0; b < blocks; b++) {
        owner[b] = 0xffffffffu;
        /* No shading held, never the scheduled one, no lights in effect,
         * never shaded; no priority key. */
        for (int k = 0; k < 4; k++)
            never[b * 8 + (size_t)k] = INT_MIN;
        never[b * 8 + 4] = -1;
        never[b * 8 + 5] = never[b * 8 + 6] = never[b * 8 + 7] = 0;
    }
    for (int i = 0; i < n; i++)
        for (int y = o->tiles[i].y / 8; y < (o->tiles[i].y + o->tiles[i].size) / 8; y++)
            for (int x = o->tiles[i].x / 8; x < (o->tiles[i].x + o->tiles[i].size) / 8; x++)
                owner[(size_t)y * (size_t)o->blocks_x + (size_t)x] = (GLuint)i;
    o->block_tile_buf = ssbo((GLsizeiptr)(blocks * sizeof(GLuint)), owner, GL_STATIC_DRAW);
    o->shaded_buf = ssbo((GLsizeiptr)(blocks * 8 * sizeof(GLint)), never, GL_DYNAMIC_DRAW);
    o->version_buf = ssbo((GLsizeiptr)((size_t)n * 2 * sizeof(GLint)), NULL, GL_STREAM_DRAW);
    o->list_buf = ssbo((GLsizeiptr)(blocks * 2 * sizeof(GLuint)), NULL, GL_DYNAMIC_DRAW);
    o->stats_buf = ssbo(OSL_STATS_UINTS * sizeof(GLuint), zero, GL_DYNAMIC_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    free(owner);
    free(never);
    free(zero);
    glGenTextures(1, &o->marks_tex);
    glBindTexture(GL_TEXTURE_2D, o->marks_tex);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_R32I, o->blocks_x, o->blocks_y);
    /* Never read yet (glClearTexImage is GL 4.4; the daemon asks for 4.3). */
    GLint *unseen = malloc(blocks * sizeof(GLint));
    if (!unseen) {
        snprintf(err, errlen, "osl: out of memory");
        return false;
    }
    for (size_t b = 0; b < blocks; b++)
        unseen[b] = INT_MIN;
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, o->blocks_x, o->blocks_y, GL_RED_INTEGER, GL_INT, unseen);
    free(unseen);

    const struct gl_stage select[] = {{GL_COMPUTE_SHADER, {"osl_select.comp"}}};
    char keys[64];
    snprintf(keys, sizeof(keys), "#define OSL_KEYS %d\n", OSL_KEYS);
    if (!(o->select_prog = gl_program_build("osl select", select, 1, keys, err, errlen)))
        return false;
    GLint max_groups = 0;
    glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 0, &max_groups);
    GLuint sp = o->select_prog;
    o->sel_frame_loc = glGetUniformLocation(sp, "u_frame_index");
    o->sel_initial_loc = glGetUniformLocation(sp, "u_initial");
    o->sel_mode_loc = glGetUniformLocation(sp, "u_mode");
    o->sel_count_loc = glGetUniformLocation(sp, "u_count");
    o->sel_count_prev_loc = glGetUniformLocation(sp, "u_count_prev");
    o->sel_blocks_loc = glGetUniformLocation(sp, "u_blocks");
    o->sel_max_groups_loc = glGetUniformLocation(sp, "u_max_groups");
    glProgramUniform2i(sp, o->sel_blocks_loc, o->blocks_x, o->blocks_y);
    glProgramUniform1i(sp, o->sel_max_groups_loc, max_groups);
    o->light_blocks_x_loc = glGetUniformLocation(o->light.prog, "u_blocks_x");
    glProgramUniform1i(o->light.prog, o->light_blocks_x_loc, o->blocks_x);
    const struct gl_stage draw[] = {
        {GL_VERTEX_SHADER, {"osl_draw.vert"}},
        {GL_FRAGMENT_SHADER, {"osl_draw.frag"}},
    };
    char mark_defines[2048];
    snprintf(mark_defines, sizeof(mark_defines), "#define OSL_SEEN 1\n%s",
             env->scene->asset ? env->defines : "");
    GLuint mark_prog = gl_program_build("osl draw (marking)", draw, 2, mark_defines, err, errlen);
    if (!mark_prog)
        return false;
    o->draw_mark = gpu_scene_program(env->gpu, mark_prog);
    glProgramUniform1i(mark_prog, glGetUniformLocation(mark_prog, "u_atlas"), SB_TEX_OSL_ATLAS);
    glProgramUniform2f(mark_prog, glGetUniformLocation(mark_prog, "u_atlas_size"),
                       (float)o->atlas_w, (float)o->atlas_h);
    o->draw_frame_loc = glGetUniformLocation(mark_prog, "u_frame_index");
    o->sel_seen_since_loc = glGetUniformLocation(sp, "u_seen_since");
    o->sel_margin_loc = glGetUniformLocation(sp, "u_margin");
    glProgramUniform1i(sp, o->sel_margin_loc, OSL_SEEN_MARGIN(o));
    o->sel_budget_loc = glGetUniformLocation(sp, "u_budget");
    glProgramUniform1i(sp, o->sel_budget_loc, o->budget_blocks);
    return true;
}

static void seen_bind(const struct osl *o)
{
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_OSL_BLOCK_TILE, o->block_tile_buf);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_OSL_SHADED, o->shaded_buf);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_OSL_VERSIONS, o->version_buf);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_OSL_LIST, o->list_buf);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_OSL_STATS, o->stats_buf);
    glBindImageTexture(SB_IMG_OSL_MARKS, o->marks_tex, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32I);
}

/* Each object's scheduled shading at frame: its last due frame s, lit with
 * the lights of s (light row frame - s), or OSL_VERSION_UNLIT when reshade
 * "touched" and no moving light reaches it at s (any shading without light
 * is the same), or 0 when the lights stand still. Selects the blocks seen
 * whose shading differs, and shades them: a pure function of frame for
 * every block the raster pass reads, as long as each was seen (or next to
 * one seen) the frame before. */
static void seen_light_pass(struct osl *o, const struct technique_env *env, int64_t frame,
                            bool initial, bool count)
{
    const struct scene *s = env->scene;
    const struct osl_options *opt = env->options;
    bool moving = s->spec.dynamic && s->spec.light_speed > 0;
    for (int i = 0; i < s->instance_count; i++) {
        int64_t due = osl_schedule_last(&o->schedule, i, frame);
        bool newly_due = due == frame && !initial;
        /* Would the schedule's shading differ from "unlit" (for the count)? */
        bool touched_due = o->change_on && moving &&
                           (opt->reshade != OSL_RESHADE_TOUCHED || osl_touched(s, i, due));
        if (o->change_on) {
            /* Keep the shading of the frame anchored while the lights' motion
             * since then cannot change it by more than the threshold; the
             * bound is only worked out when the schedule moves on. */
            int64_t *a = &o->anchor[i];
            if (initial || *a == INT64_MIN || frame - *a >= o->light_rows)
                *a = due;
            else if (newly_due && *a != due) {
                if (osl_change_bound(s, i, *a, due, o->change_lipschitz) > opt->change_threshold)
                    *a = due;
                else if (count && (touched_due || osl_touched(s, i, *a)))
                    o->change_saved++; /* kept where the schedule would reshade */
            }
            due = *a;
        }
        if (o->change_on && count && newly_due && (touched_due || osl_touched(s, i, due)))
            o->change_due++; /* a reshade the schedule asked for, kept or not */
        GLint version = (GLint)due;
        if (!moving)
            version = 0;
        else if (opt->reshade == OSL_RESHADE_TOUCHED && !osl_touched(s, i, due))
            version = OSL_VERSION_UNLIT;
        o->versions[i * 2] = version;
        o->versions[i * 2 + 1] = (GLint)(frame - due);
    }
    int rows = o->light_rows;
    for (int r = 0; r < rows; r++)
        o->rows[r] = frame - r;
    gpu_scene_set_light_rows(env->gpu, o->rows, rows);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, o->version_buf);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0,
                    (GLsizeiptr)((size_t)s->instance_count * 2 * sizeof(GLint)), o->versions);
    static const GLuint none[4];
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, o->stats_buf);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof(none), none);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);

    /* The raster pass's marks of the frame before, then the selection. */
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    seen_bind(o);
    glUseProgram(o->select_prog);
    glUniform1i(o->sel_frame_loc, (GLint)frame);
    glUniform1i(o->sel_initial_loc, initial);
    glUniform1i(o->sel_count_loc, count);
    /* The frame before counts when it was a timed frame rendered just before. */
    glUniform1i(o->sel_count_prev_loc, !initial && o->last_counted && o->last_frame == frame - 1);
    o->last_counted = false;
    glUniform1i(o->sel_mode_loc, 0);
    /* A still camera sees the same blocks every frame: the first frame's
     * marks stand for all. */
    glUniform1i(o->sel_seen_since_loc, o->camera_moves ? (GLint)(frame - 1) : INT_MIN + 1);
    GLuint blocks = (GLuint)o->blocks_x * (GLuint)o->blocks_y;
    glDispatchCompute((blocks + 63) / 64, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    if (o->budget_blocks >= 0) {
        /* The cut by priority (one invocation), then the candidates above it. */
        glUniform1i(o->sel_mode_loc, 3);
        glDispatchCompute(1, 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        glUniform1i(o->sel_mode_loc, 4);
        glDispatchCompute((blocks + 63) / 64, 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }
    glUniform1i(o->sel_mode_loc, 1);
    glDispatchCompute(1, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);

    bind_light_inputs(o, env);
    seen_bind(o);
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, o->stats_buf);
    /* Whole in timed frames; in ranges where the harness slices (the
     * first shading of every seen block, in the measuring frame). */
    gpu_dispatch_indirect(env->budget, 0, o->group_base_loc, o->group_end_loc, o->groups_x_max);
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
}

static void osl_destroy(void *state);

static bool osl_create(const struct technique_env *env, void **state, char *err,
                       size_t errlen)
{
    const struct scene *s = env->scene;
    int n = s->instance_count;
    struct osl *o = calloc(1, sizeof(*o));
    if (!o)
        goto oom;
    *state = o;
    o->tiles = calloc((size_t)n, sizeof(*o->tiles));
    o->plan = calloc((size_t)n, sizeof(*o->plan));
    o->work = calloc((size_t)n * 4, sizeof(GLuint));
    o->frames = env->frames;
    double *dist = calloc((size_t)n, sizeof(double));
    if (!o->tiles || !o->plan || !o->work || !dist) {
        free(dist);
        goto oom;
    }
    for (int i = 0; i < n; i++)
        dist[i] = scene_instance_distance(s, i);
    const struct osl_options *opt = env->options;
    bool sched = osl_schedule_init(&o->schedule, dist, n, opt->async_distance);
    free(dist);
    /* Room for change detection's older shading too (light_rows). */
    o->rows = calloc((size_t)o->schedule.max_period + OSL_CHANGE_ROWS, sizeof(int64_t));
    if (!sched || !o->rows)
        goto oom;

    o->textured = s->asset != NULL;
    int max_tex = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_tex);
    if (!choose_tiles(o, env, max_tex, err, errlen) ||
        !check_limits(o, env, &max_tex, err, errlen))
        goto fail;

    const struct gl_stage texgen[] = {
        {GL_VERTEX_SHADER, {"osl_texgen.vert"}},
        {GL_FRAGMENT_SHADER, {"osl_texgen.frag"}},
    };
    const struct gl_stage light[] = {{GL_COMPUTE_SHADER, {"osl_light.comp"}}};
    const struct gl_stage draw[] = {
        {GL_VERTEX_SHADER, {"osl_draw.vert"}},
        {GL_FRAGMENT_SHADER, {"osl_draw.frag"}},
    };
    GLuint light_prog = 0, draw_prog = 0;
    o->seen_asked = opt->visibility == OSL_VISIBILITY_SEEN;
    o->seen = o->seen_asked && s->spec.dynamic && s->spec.light_speed > 0;
    o->camera_moves = scene_camera_moves(s);
    /* Whole blocks: a budget under one block still shades what must be. */
    o->budget_blocks = opt->budget_texels > 0 ? opt->budget_texels / 64 : -1;
    o->light_rows = o->schedule.max_period > 0 ? o->schedule.max_period : 1;
    if (o->seen && opt->change_threshold > 0) {
        const char *defs = env->defines ? env->defines : "";
        if (strstr(defs, "LIGHTING_PBR"))
            o->change_why = "the bound covers Phong and Blinn-Phong, not PBR's BRDF";
        else {
            o->change_on = true;
            /* Phong's motion bound; Blinn-Phong's half vector and shadows'
             * visibility have none, so only the range bound holds there. */
            o->change_lipschitz =
                !strstr(defs, "LIGHTING_BLINN_PHONG") && !strstr(defs, "LOOK_SHADOWS");
            o->light_rows += OSL_CHANGE_ROWS;
            o->anchor = malloc((size_t)n * sizeof(int64_t));
            if (!o->anchor)
                goto oom;
            for (int i = 0; i < n; i++)
                o->anchor[i] = INT64_MIN;
        }
    }
    char light_defines[2048];
    snprintf(light_defines, sizeof(light_defines), "%s%s", env->defines ? env->defines : "",
             o->seen ? "#define OSL_BLOCK_LIST 1\n" : "");
    /* Asset scenes bake their materials in texture generation and cut the
     * mask's holes in the raster pass, both through surface.glsl: those
     * programs take the scene's defines (SCENE_TEXTURED) there only, so the
     * procedural scenes' programs stay the text they always were. */
    const char *scene_defines = s->asset ? env->defines : NULL;
    if (!(o->texgen_prog = gl_program_build("osl texgen", texgen, 2, scene_defines, err, errlen)) ||
        !(light_prog = gl_program_build("osl lighting", light, 1, light_defines, err, errlen)) ||
        !(draw_prog = gl_program_build("osl draw", draw, 2, scene_defines, err, errlen))) {
        glDeleteProgram(light_prog);
        goto fail;
    }
    o->light = gpu_scene_program(env->gpu, light_prog);
    o->draw = gpu_scene_program(env->gpu, draw_prog);
    o->work_count_loc = glGetUniformLocation(light_prog, "u_work_count");
    o->groups_x_loc = glGetUniformLocation(light_prog, "u_groups_x");
    o->group_base_loc = glGetUniformLocation(light_prog, "u_group_base");
    o->group_end_loc = glGetUniformLocation(light_prog, "u_group_end");
    /* Texture units never change: the geometry atlas for the lighting
     * pass, the shading atlas on unit 0 for the raster pass. */
    glProgramUniform1i(light_prog, glGetUniformLocation(light_prog, "u_position"),
                       SB_TEX_OSL_GEO_POSITION);
    glProgramUniform1i(light_prog, glGetUniformLocation(light_prog, "u_normal"),
                       SB_TEX_OSL_GEO_NORMAL);
    if (o->textured) {
        glProgramUniform1i(light_prog, glGetUniformLocation(light_prog, "u_albedo"),
                           SB_TEX_OSL_GEO_ALBEDO);
        glProgramUniform1i(light_prog, glGetUniformLocation(light_prog, "u_surface"),
                           SB_TEX_OSL_GEO_SURFACE);
    }
    glProgramUniform1i(draw_prog, glGetUniformLocation(draw_prog, "u_atlas"), SB_TEX_OSL_ATLAS);

    if (!generate_textures(o, env, err, errlen))
        goto fail;
    glGenTextures(1, &o->atlas);
    glBindTexture(GL_TEXTURE_2D, o->atlas);
    glTexStorage2D(GL_TEXTURE_2D, 1, OSL_ATLAS_FORMAT(o), o->atlas_w, o->atlas_h);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glProgramUniform2f(o->draw.prog, glGetUniformLocation(o->draw.prog, "u_atlas_size"),
                       (float)o->atlas_w, (float)o->atlas_h);

    GLint *tile_data = calloc((size_t)n * 4, sizeof(GLint));
    if (!tile_data)
        goto oom;
    for (int i = 0; i < n; i++) {
        const struct atlas_tile *geo = &o->geo[o->geo_entry[i]];
        tile_data[i * 4 + 0] = o->tiles[i].x;
        tile_data[i * 4 + 1] = o->tiles[i].y;
        tile_data[i * 4 + 2] = o->tiles[i].size;
        /* Where the instance's geometry lies in the geometry atlas, packed
         * as x + y * 65536 (both below the device's texture size). */
        tile_data[i * 4 + 3] = geo->x + geo->y * 65536;
    }
    glGenBuffers(1, &o->tile_buffer);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, o->tile_buffer);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((size_t)n * 4 * sizeof(GLint)),
                 tile_data, GL_STATIC_DRAW);
    free(tile_data);
    glGenBuffers(1, &o->work_buffer);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, o->work_buffer);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((size_t)n * 4 * sizeof(GLuint)),
                 NULL, GL_STREAM_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    if (o->seen && !seen_create(o, env, err, errlen))
        goto fail;
    return true;
oom:
    snprintf(err, errlen, "osl: out of memory");
fail:
    osl_destroy(o);
    *state = NULL;
    return false;
}

/* Dispatches the lighting pass for the planned objects. Returns texels shaded. */
static double light_pass(struct osl *o, const struct technique_env *env, int64_t frame,
                         int count)
{
    int rows = 1;
    uint32_t blocks = 0;
    double texels = 0;
    for (int k = 0; k < count; k++) {
        int i = o->plan[k].instance, per_row = o->tiles[i].size / 8;
        int row = (int)(frame - o->plan[k].time);
        if (row + 1 > rows)
            rows = row + 1;
        o->work[k * 4 + 0] = (GLuint)i;
        o->work[k * 4 + 1] = (GLuint)row;
        o->work[k * 4 + 2] = blocks;
        o->work[k * 4 + 3] = (GLuint)per_row;
        blocks += (uint32_t)(per_row * per_row);
        texels += (double)o->tiles[i].size * o->tiles[i].size;
    }
    for (int r = 0; r < rows; r++)
        o->rows[r] = frame - r;
    gpu_scene_set_light_rows(env->gpu, o->rows, rows);

    glBindBuffer(GL_SHADER_STORAGE_BUFFER, o->work_buffer);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((size_t)count * 4 * sizeof(GLuint)),
                 o->work, GL_STREAM_DRAW);
    bind_light_inputs(o, env);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_OSL_WORK, o->work_buffer);
    glUniform1i(o->work_count_loc, count);
    /* The blocks in ranges of bounded cost (all at once unless that is
     * costly): each a dispatch of its own. */
    struct gpu_tiles t;
    for (gpu_range_begin(env->budget, (int)blocks, &t); gpu_tiles_next(env->budget, &t);) {
        uint32_t n = (uint32_t)t.tw;
        uint32_t gx = n < (uint32_t)o->groups_x_max ? n : (uint32_t)o->groups_x_max;
        uint32_t gy = (n + gx - 1) / gx;
        glUniform1i(o->groups_x_loc, (GLint)gx);
        glUniform1ui(o->group_base_loc, (GLuint)t.tx);
        glUniform1ui(o->group_end_loc, (GLuint)(t.tx + t.tw));
        glDispatchCompute(gx, gy, 1);
    }
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
    return texels;
}

static bool osl_render(void *state, const struct technique_env *env, int64_t frame,
                       char *err, size_t errlen)
{
    struct osl *o = state;
    if (o->seen) {
        o->pixels = (double)env->width * env->height;
        bool counted = frame >= 1 && frame <= o->frames;
        seen_light_pass(o, env, frame, !o->shaded_once, counted);
        o->timed_frames += counted;
        o->shaded_once = true;
        gpu_pass_begin(env->passes, PASS_RASTER, env->output_fbo, env->width, env->height);
        glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        bool mark = o->camera_moves || !o->marked_once;
        const struct scene_program *draw = mark ? &o->draw_mark : &o->draw;
        gpu_scene_bind(env->gpu, draw);
        if (mark)
            glUniform1i(o->draw_frame_loc, (GLint)frame);
        o->marked_once = true;
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_OSL_TILES, o->tile_buffer);
        seen_bind(o);
        o->last_frame = frame;
        o->last_counted = counted; /* a still camera reads its first marks every frame */
        glActiveTexture(GL_TEXTURE0 + SB_TEX_OSL_ATLAS);
        glBindTexture(GL_TEXTURE_2D, o->atlas);
        struct gpu_tiles t;
        for (gpu_tiles_begin(env->budget, env->width, env->height, &t); gpu_tiles_next(env->budget, &t);)
            gpu_scene_draw(env->gpu, draw);
        gpu_pass_end(env->passes);
        return technique_keep_going(env, err, errlen);
    }
    int count = osl_schedule_plan(&o->schedule, env->scene, frame, !o->shaded_once,
                                  ((const struct osl_options *)env->options)->reshade, o->plan);
    double texels = count ? light_pass(o, env, frame, count) : 0.0;
    if (!o->shaded_once) {
        o->initial_objects = count;
        o->initial_texels = texels;
    }
    if (frame >= 1 && frame <= o->frames) {
        o->timed_frames++;
        /* The first frame drawn shades everything once; that is set-up, reported
         * apart, unless there was no warm-up to absorb it. */
        o->reshaded_sum += count;
        o->texels_sum += texels;
        if (count > o->reshaded_max)
            o->reshaded_max = count;
        if (texels > o->texels_max)
            o->texels_max = texels;
    }
    o->shaded_once = true;

    gpu_pass_begin(env->passes, PASS_RASTER, env->output_fbo, env->width, env->height);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    gpu_scene_bind(env->gpu, &o->draw);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_OSL_TILES, o->tile_buffer);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_OSL_ATLAS);
    glBindTexture(GL_TEXTURE_2D, o->atlas);
    struct gpu_tiles t;
    for (gpu_tiles_begin(env->budget, env->width, env->height, &t); gpu_tiles_next(env->budget, &t);)
        gpu_scene_draw(env->gpu, &o->draw);
    gpu_pass_end(env->passes);
    return technique_keep_going(env, err, errlen);
}

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

/* Objects with a block read (the marks hold the last frame each block was
 * read: with a still camera, the first frame's reads), and objects with a
 * block shaded in a timed frame, and objects shaded in a timed frame with
 * no block read. Read back once, after the run. */
static void seen_objects(const struct osl *o, int out[3])
{
    size_t blocks = (size_t)o->blocks_x * (size_t)o->blocks_y;
    int n = o->schedule.count;
    GLint *marks = malloc(blocks * sizeof(GLint));
    GLint *shaded = malloc(blocks * 8 * sizeof(GLint));
    GLuint *owner = malloc(blocks * sizeof(GLuint));
    unsigned char *flags = calloc((size_t)n, 1);
    if (!marks || !shaded || !owner || !flags)
        goto done;
    glBindTexture(GL_TEXTURE_2D, o->marks_tex);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glGetTexImage(GL_TEXTURE_2D, 0, GL_RED_INTEGER, GL_INT, marks);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, o->shaded_buf);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(blocks * 8 * sizeof(GLint)),
                       shaded);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, o->block_tile_buf);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(blocks * sizeof(GLuint)), owner);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    for (size_t b = 0; b < blocks; b++) {
        if (owner[b] >= (GLuint)n)
            continue;
        if (marks[b] != INT_MIN)
            flags[owner[b]] |= 1;
        if (shaded[b * 8 + 3] >= 1 && shaded[b * 8 + 3] <= o->frames)
            flags[owner[b]] |= 2;
    }
    out[0] = out[1] = out[2] = 0;
    for (int i = 0; i < n; i++) {
        out[0] += flags[i] & 1;
        out[1] += (flags[i] >> 1) & 1;
        out[2] += flags[i] == 2; /* reshaded, never read */
    }
done:
    free(marks);
    free(shaded);
    free(owner);
    free(flags);
}

static json_t *osl_describe(void *state)
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
    if (o->seen) {
        /* Counted on the GPU over the timed frames; read once, here, after
         * checking the last frame's reads (the next frame would have). */
        if (o->last_counted) {
            glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
            seen_bind(o);
            glUseProgram(o->select_prog);
            glUniform1i(o->sel_frame_loc, (GLint)(o->last_frame + 1));
            glUniform1i(o->sel_count_prev_loc, 1);
            glUniform1i(o->sel_mode_loc, 2);
            glDispatchCompute(((GLuint)o->blocks_x * (GLuint)o->blocks_y + 63) / 64, 1, 1);
            glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
            o->last_counted = false;
        }
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, o->stats_buf);
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof(stats), stats);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        o->texels_sum = 64.0 * stats[4];
        o->texels_max = 64.0 * stats[5];
        o->stale_blocks = stats[6];
        seen_objects(o, objects);
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
    if (d && o->asset_texels > 0)
        json_object_set_new(d, "asset_charts",
                            json_pack("{s:f, s:f, s:f, s:i}", "texels", o->asset_texels,
                                      "uncovered_share", o->asset_uncovered / o->asset_texels,
                                      "gutter_filled_share", o->asset_filled / o->asset_texels,
                                      "gutter_texels", OSL_GUTTER_TEXELS));
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

static void osl_destroy(void *state)
{
    struct osl *o = state;
    if (!o)
        return;
    glDeleteProgram(o->texgen_prog);
    glDeleteProgram(o->light.prog);
    glDeleteProgram(o->draw.prog);
    glDeleteTextures(1, &o->geo_position);
    glDeleteTextures(1, &o->geo_normal);
    glDeleteTextures(1, &o->geo_albedo);
    glDeleteTextures(1, &o->geo_surface);
    free(o->geo);
    free(o->geo_entry);
    glDeleteTextures(1, &o->atlas);
    glDeleteBuffers(1, &o->tile_buffer);
    glDeleteBuffers(1, &o->work_buffer);
    glDeleteProgram(o->select_prog);
    glDeleteProgram(o->draw_mark.prog);
    GLuint seen_bufs[] = {o->block_tile_buf, o->shaded_buf, o->version_buf, o->list_buf,
                          o->stats_buf};
    glDeleteBuffers(5, seen_bufs);
    glDeleteTextures(1, &o->marks_tex);
    free(o->versions);
    free(o->anchor);
    osl_schedule_finish(&o->schedule);
    free(o->tiles);
    free(o->plan);
    free(o->work);
    free(o->rows);
    free(o);
}

const struct technique technique_osl = {
    .info = &osl_info,
    .create = osl_create,
    .render = osl_render,
    .describe = osl_describe,
    .destroy = osl_destroy,
};
