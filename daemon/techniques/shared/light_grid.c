#define _POSIX_C_SOURCE 200809L
#include "daemon/techniques/shared/light_grid.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/result_keys.h"
#include "common/clock.h"
#include "common/log.h"
#include "common/stats.h"
#include "daemon/gpu/bindings.h"
#include "daemon/gpu/glutil.h"
#include "daemon/scene/light_shape.h"

/* Index entries a frame's lists may take at most (64 MiB, times the ring),
 * whatever the device allows: past it a scene is better served by larger
 * cells. */
static const long long INDEX_BUDGET = 16LL * 1024 * 1024;
/* The CPU path also fills a host copy: a smaller budget. */
static const long long CPU_INDEX_BUDGET = 8LL * 1024 * 1024;
enum { GROUP = 64 }; /* local size of the scatter and compaction passes */

static double mib(double bytes) { return bytes / (1024.0 * 1024.0); }

static const char *field_name(const struct light_grid_config *cfg, char *buf, size_t cap,
                              const char *option)
{
    snprintf(buf, cap, "%s.%s", cfg->technique, option);
    return buf;
}

/* The depth range the slices span: the nearest and farthest view depth of
 * any object's box, within the clip planes. Slices spent on empty space in
 * front of the scene would only make the occupied ones coarser (Filament's
 * froxelizer starts its slices at a "light near" for the same reason); the
 * first and last slices still reach the clip planes, so every pixel has a
 * cell. Boxes rather than bounding spheres: a ground plane's sphere would
 * stretch the range far beyond the plane. */
static void slice_range(const struct scene *s,
                        const struct scene_camera *cam, float out[2])
{
    float lo = cam->far_z, hi = cam->near_z;
    const float *v = cam->view;
    for (int i = 0; i < s->instance_count; i++) {
        const struct scene_instance *in = &s->instances[i];
        const struct mesh *m = &s->meshes[in->mesh];
        for (int corner = 0; corner < 8; corner++) {
            float p[3];
            for (int k = 0; k < 3; k++)
                p[k] = in->pos[k] + in->scale * (corner >> k & 1 ? m->box_max[k] : m->box_min[k]);
            float z = -(v[2] * p[0] + v[6] * p[1] + v[10] * p[2] + v[14]);
            lo = fminf(lo, z);
            hi = fmaxf(hi, z);
        }
    }
    lo = fmaxf(lo, cam->near_z);
    hi = fminf(hi, cam->far_z);
    if (!(hi > lo * 1.001f))
        lo = cam->near_z, hi = cam->far_z;
    out[0] = lo, out[1] = hi;
}

/* The slices' depth range and scale for camera cam, into the block. */
static void set_slices(struct light_grid *g, const struct scene *s, const struct scene_camera *cam)
{
    float range[2];
    slice_range(s, cam, range);
    bool exponential = g->cfg.slices == CLUSTER_SLICES_EXPONENTIAL;
    double span = exponential ? log(range[1] / range[0]) : range[1] - range[0];
    g->block.slices[0] = range[0];
    g->block.slices[1] = range[1];
    g->block.slices[2] = (float)(g->block.dims[2] / span);
    g->block.slices[3] = exponential ? 1.0f : 0.0f;
}

static GLuint make_buffer(double bytes, double *total)
{
    GLuint b = 0;
    glGenBuffers(1, &b);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, b);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(bytes > 0 ? bytes : 16), NULL,
                 GL_DYNAMIC_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    *total += bytes;
    return b;
}

static GLuint build_compute(const char *label, const char *file, const char *defines, char *err,
                            size_t errlen)
{
    const struct gl_stage stage[] = {{GL_COMPUTE_SHADER, {file}}};
    return gl_program_build(label, stage, 1, defines, err, errlen);
}

/* The bit buffer within GL_MAX_SHADER_STORAGE_BLOCK_SIZE (the index buffer
 * is cut to fit) and every dispatch within the work-group counts, or a
 * message naming the option to change. */
static bool check_device(const struct light_grid *g, const struct technique_env *env,
                         double bits_bytes, char *err, size_t errlen)
{
    const struct gpu_caps *caps = env->caps;
    const struct light_grid_config *cfg = &g->cfg;
    bool tiles = cfg->kind == LIGHT_GRID_TILES;
    char field[96];
    const char *grid_field = field_name(cfg, field, sizeof(field), tiles ? "tile_size" : "grid");
    double max = (double)caps->max_ssbo_bytes;
    if (max > 0 && bits_bytes > max) {
        snprintf(err, errlen,
                 "%s: binning %d lights into %d cells needs a %.1f MiB bit buffer; this device "
                 "allows %.1f MiB per storage buffer (GL_MAX_SHADER_STORAGE_BLOCK_SIZE): use "
                 "fewer cells",
                 grid_field, g->lights, g->cells, mib(bits_bytes), mib(max));
        return false;
    }
    long long groups_cells = (g->cells + GROUP - 1) / GROUP;
    const int *count = caps->max_compute_work_group_count;
    if (groups_cells > count[0] || (long long)g->scatter_groups[1] > count[1] ||
        (tiles && (g->block.dims[0] > count[0] || g->block.dims[1] > count[1]))) {
        snprintf(err, errlen,
                 "%s: %d cells (%lld work groups of %d) or %d lights "
                 "exceed this device's compute work-group counts "
                 "(GL_MAX_COMPUTE_WORK_GROUP_COUNT %d x %d)",
                 grid_field, g->cells, groups_cells, GROUP, g->lights, count[0], count[1]);
        return false;
    }
    if (caps->max_compute_invocations < GROUP || caps->max_compute_work_group_size[0] < GROUP) {
        snprintf(err, errlen, "%s: this device runs fewer than %d compute invocations a group",
                 cfg->technique, GROUP);
        return false;
    }
    return true;
}

bool light_grid_init(struct light_grid *g, const struct technique_env *env,
                     const struct light_grid_config *cfg, char *err, size_t errlen)
{
    memset(g, 0, sizeof(*g));
    g->cfg = *cfg;
    g->width = env->width, g->height = env->height;
    g->lights = env->scene->light_count;
    g->frames = env->frames;
    g->camera_moves = scene_camera_moves(env->scene);
    bool tiles = cfg->kind == LIGHT_GRID_TILES;
    bool cpu = tiles && cfg->binning == LIGHT_BINNING_CPU;
    char field[96];
    int dims[3], tw, th;
    if (tiles) {
        tw = th = cfg->tile_size;
        dims[0] = (env->width + tw - 1) / tw;
        dims[1] = (env->height + th - 1) / th;
        dims[2] = 1;
    } else {
        if (cfg->grid[0] > env->width || cfg->grid[1] > env->height) {
            snprintf(err, errlen, "%s: %d x %d tiles do not fit a %d x %d image (a tile is at "
                     "least one pixel)", field_name(cfg, field, sizeof(field), "grid"),
                     cfg->grid[0], cfg->grid[1], env->width, env->height);
            return false;
        }
        tw = (env->width + cfg->grid[0] - 1) / cfg->grid[0];
        th = (env->height + cfg->grid[1] - 1) / cfg->grid[1];
        memcpy(dims, cfg->grid, sizeof(dims));
    }
    g->cells = dims[0] * dims[1] * dims[2];
    g->words = (g->lights + 31) / 32;
    if (g->words < 1)
        g->words = 1;
    /* Lists are packed one after another, so the index buffer needs what
     * the frame's lists take, not cells x the bound: its capacity is the
     * worst case, cut to a budget and the device's limit; a list that finds
     * it full overflows like one over the bound (counted, never silent). */
    long long budget = cpu ? CPU_INDEX_BUDGET : INDEX_BUDGET;
    long long per_cell = g->lights > 0 ? g->lights : 1;
    if (!tiles && cfg->max_per_cell < per_cell)
        per_cell = cfg->max_per_cell;
    g->capacity = (long long)g->cells * per_cell;
    if (g->capacity > budget)
        g->capacity = budget;
    if (env->caps->max_ssbo_bytes > 0 && g->capacity * 4 > env->caps->max_ssbo_bytes)
        g->capacity = env->caps->max_ssbo_bytes / 4;
    g->block = (struct light_grid_block){
        .dims = {dims[0], dims[1], dims[2], g->cells},
        .tile = {(float)tw, (float)th, 1.0f / (float)tw, 1.0f / (float)th},
        .lists = {tiles ? 0 : cfg->max_per_cell, (int32_t)g->capacity, g->words,
                  tiles || cfg->overflow == CLUSTER_OVERFLOW_FALLBACK},
        .counts = {g->lights, 0, (g->words + 31) / 32, 0},
    };
    struct scene_camera cam;
    scene_camera_at(env->scene, 0, &cam);
    set_slices(g, env->scene, &cam);
    double bits_bytes = cpu ? 0 : (double)g->cells * g->words * 4.0;
    int row = env->caps->max_compute_work_group_count[0] > 0
                  ? env->caps->max_compute_work_group_count[0] : 65535;
    int groups = (g->lights + GROUP - 1) / GROUP;
    g->scatter_groups[0] = groups < row ? groups : row;
    g->scatter_groups[1] = groups ? (groups + row - 1) / row : 0;
    if (!check_device(g, env, bits_bytes, err, errlen))
        return false;

    glGenBuffers(LIGHT_GRID_RING, g->ubo);
    for (int r = 0; r < LIGHT_GRID_RING; r++) {
        glBindBuffer(GL_UNIFORM_BUFFER, g->ubo[r]);
        glBufferData(GL_UNIFORM_BUFFER, sizeof(g->block), &g->block, GL_DYNAMIC_DRAW);
    }
    glBindBuffer(GL_UNIFORM_BUFFER, 0);
    for (int r = 0; r < LIGHT_GRID_RING; r++) {
        g->cells_buf[r] = make_buffer((double)g->cells * 8.0, &g->buffer_bytes);
        g->index_buf[r] = make_buffer((double)g->capacity * 4.0, &g->buffer_bytes);
    }
    g->stats_buf = make_buffer((double)(g->frames + 1) * sizeof(struct light_grid_stats),
                               &g->buffer_bytes);
    g->stats = calloc((size_t)g->frames + 1, sizeof(*g->stats));
    g->bin_ms = calloc((size_t)g->frames + 1, sizeof(double));
    if (!g->stats || !g->bin_ms) {
        snprintf(err, errlen, "%s: out of memory", cfg->technique);
        return false;
    }
    if (cpu) {
        g->rects = malloc((size_t)(g->lights ? g->lights : 1) * 4 * sizeof(int));
        g->counts = malloc((size_t)g->cells * sizeof(uint32_t));
        g->cells_host = malloc((size_t)g->cells * 2 * sizeof(uint32_t));
        g->index_host = malloc((size_t)g->capacity * sizeof(uint32_t));
        if (!g->rects || !g->counts || !g->cells_host || !g->index_host) {
            snprintf(err, errlen, "%s: out of memory for the CPU light grid", cfg->technique);
            return false;
        }
        return true;
    }
    /* Zero once: compaction leaves them zero for the next frame. */
    g->bits_buf = make_buffer(bits_bytes, &g->buffer_bytes);
    g->summary_buf = make_buffer((double)g->cells * g->block.counts[2] * 4.0, &g->buffer_bytes);
    GLuint zeroed[2] = {g->bits_buf, g->summary_buf};
    for (int i = 0; i < 2; i++) {
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, zeroed[i]);
        glClearBufferData(GL_SHADER_STORAGE_BUFFER, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT,
                          NULL);
    }
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    const char *defines = tiles ? "#define GRID_TILES 1\n" : "";
    if (tiles) {
        g->tile_depth_buf = make_buffer((double)g->cells * 8.0, &g->buffer_bytes);
        /* A multisampled depth is read sample by sample (msaa.glsl). */
        char depth_defines[64];
        snprintf(depth_defines, sizeof(depth_defines), "%s", defines);
        if (env->samples > 1)
            snprintf(depth_defines + strlen(depth_defines),
                     sizeof(depth_defines) - strlen(depth_defines),
                     "#define SB_MSAA_SAMPLES %d\n", env->samples);
        if (!(g->depth_prog = build_compute("tile depth bounds", "tile_depth.comp", depth_defines,
                                            err, errlen)))
            return false;
    }
    return (g->scatter_prog = build_compute("light scatter", "light_scatter.comp", defines, err,
                                            errlen)) &&
           (g->compact_prog = build_compute("light compaction", "light_compact.comp", defines,
                                            err, errlen));
}

void light_grid_finish(struct light_grid *g)
{
    if (!g)
        return;
    glDeleteProgram(g->depth_prog);
    glDeleteProgram(g->scatter_prog);
    glDeleteProgram(g->compact_prog);
    glDeleteBuffers(LIGHT_GRID_RING, g->ubo);
    glDeleteBuffers(LIGHT_GRID_RING, g->cells_buf);
    glDeleteBuffers(LIGHT_GRID_RING, g->index_buf);
    glDeleteBuffers(1, &g->tile_depth_buf);
    glDeleteBuffers(1, &g->bits_buf);
    glDeleteBuffers(1, &g->summary_buf);
    glDeleteBuffers(1, &g->stats_buf);
    free(g->stats);
    free(g->bin_ms);
    free(g->rects);
    free(g->counts);
    free(g->cells_host);
    free(g->index_host);
    memset(g, 0, sizeof(*g));
}

static int stats_slot(const struct light_grid *g, int64_t frame)
{
    return frame >= 1 && frame <= g->frames ? (int)frame : 0;
}

/* Seed 003's CPU-built grid: each light's tight screen rectangle (no depth
 * bounds: the depth buffer lives on the GPU) appended to the tiles it
 * covers, in light order, then uploaded. A spot light's rectangle is its
 * cone's bounding sphere's (no cone test per tile here); a directional
 * light's the whole screen. */
static void build_cpu(struct light_grid *g, const struct technique_env *env, int64_t frame,
                      int slot, const struct scene_camera *cam)
{
    const struct scene *s = env->scene;
    const int tw = (int)g->block.tile[0], th = (int)g->block.tile[1], tx = g->block.dims[0];
    memset(g->counts, 0, (size_t)g->cells * sizeof(uint32_t));
    for (int i = 0; i < g->lights; i++) {
        float p[3], centre[3], radius;
        int *r = &g->rects[i * 4];
        scene_light_position(s, i, frame, p);
        /* A spot light by its cone's bounding sphere; a directional light
         * in every tile. */
        if (!scene_light_bound(&s->lights[i], p, centre, &radius)) {
            r[0] = r[1] = 0, r[2] = g->width, r[3] = g->height;
        } else if (!light_rect(LIGHT_BOUNDS_SCISSOR_TIGHT, centre, radius, cam->view,
                               cam->proj, cam->view_proj, cam->near_z, cam->far_z, g->width,
                               g->height, r)) {
            r[0] = 1, r[2] = 0; /* no tile */
            continue;
        }
        /* Tiles covered, inclusive. */
        r[0] /= tw, r[1] /= th, r[2] = (r[2] - 1) / tw, r[3] = (r[3] - 1) / th;
        for (int y = r[1]; y <= r[3]; y++)
            for (int x = r[0]; x <= r[2]; x++)
                g->counts[y * tx + x]++;
    }
    struct light_grid_stats st = {0};
    uint32_t next = 0;
    for (int c = 0; c < g->cells; c++) {
        uint32_t n = g->counts[c];
        bool fits = (long long)next + n <= g->capacity;
        g->cells_host[c * 2] = fits ? next : 0;
        g->cells_host[c * 2 + 1] = fits ? n : 0x80000000u;
        if (!fits) {
            st.overflow_cells++;
            st.lights_dropped += n;
        } else {
            next += n;
            st.kept += n;
        }
        if (n)
            st.nonempty++;
        if (n > st.fullest)
            st.fullest = n;
        g->counts[c] = g->cells_host[c * 2]; /* now each tile's write cursor */
    }
    st.handed_out = next;
    for (int i = 0; i < g->lights; i++) {
        const int *r = &g->rects[i * 4];
        for (int y = r[1]; y <= r[3]; y++)
            for (int x = r[0]; x <= r[2]; x++) {
                int c = y * tx + x;
                if (!(g->cells_host[c * 2 + 1] & 0x80000000u))
                    g->index_host[g->counts[c]++] = (uint32_t)i;
            }
    }
    g->stats[slot] = st;
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->cells_buf[g->ring]);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)((size_t)g->cells * 8),
                    g->cells_host);
    if (next) {
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->index_buf[g->ring]);
        glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)((size_t)next * 4),
                        g->index_host);
    }
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
}

void light_grid_build(struct light_grid *g, const struct technique_env *env, int64_t frame)
{
    double t0 = clock_mono_s();
    int slot = stats_slot(g, frame);
    bool cpu = g->cfg.kind == LIGHT_GRID_TILES && g->cfg.binning == LIGHT_BINNING_CPU;
    struct scene_camera cam;
    if (cpu || g->camera_moves)
        scene_camera_at(env->scene, frame, &cam);
    if (g->camera_moves && g->cfg.kind == LIGHT_GRID_CLUSTERS)
        set_slices(g, env->scene, &cam);
    g->block.counts[1] = slot;
    g->ring = (g->ring + 1) % LIGHT_GRID_RING;
    glBindBuffer(GL_UNIFORM_BUFFER, g->ubo[g->ring]);
    glBufferSubData(GL_UNIFORM_BUFFER, 0, sizeof(g->block), &g->block);
    glBindBuffer(GL_UNIFORM_BUFFER, 0);
    glBindBufferBase(GL_UNIFORM_BUFFER, SB_UBO_LIGHT_GRID, g->ubo[g->ring]);
    if (cpu) {
        build_cpu(g, env, frame, slot, &cam);
    } else {
        /* Zero this frame's record (the bits are zero already). */
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->stats_buf);
        glClearBufferSubData(GL_SHADER_STORAGE_BUFFER, GL_R32UI,
                             (GLintptr)((size_t)slot * sizeof(struct light_grid_stats)),
                             sizeof(struct light_grid_stats), GL_RED_INTEGER, GL_UNSIGNED_INT,
                             NULL);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_LIGHTS, env->gpu->light_buffer);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_LIGHT_POSITIONS,
                         env->gpu->position_buffer);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_LIGHT_BITS, g->bits_buf);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_LIGHT_SUMMARY, g->summary_buf);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_LIGHT_GRID, g->cells_buf[g->ring]);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_LIGHT_INDICES, g->index_buf[g->ring]);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_CULL_STATS, g->stats_buf);
        if (g->cfg.kind == LIGHT_GRID_TILES) {
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_TILE_DEPTH, g->tile_depth_buf);
            glActiveTexture(GL_TEXTURE0 + SB_TEX_DEPTH);
            glBindTexture(gpu_targets_kind(env->targets, env->output_depth), env->output_depth);
            glActiveTexture(GL_TEXTURE0);
            glUseProgram(g->depth_prog);
            glDispatchCompute((GLuint)g->block.dims[0], (GLuint)g->block.dims[1], 1);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        }
        if (g->lights > 0) {
            /* An invocation per light, in rows of at most the device's count. */
            glUseProgram(g->scatter_prog);
            glDispatchCompute((GLuint)g->scatter_groups[0], (GLuint)g->scatter_groups[1], 1);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        }
        glUseProgram(g->compact_prog);
        glDispatchCompute((GLuint)((g->cells + GROUP - 1) / GROUP), 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }
    if (slot)
        g->bin_ms[slot] = (clock_mono_s() - t0) * 1e3;
}

void light_grid_bind(const struct light_grid *g)
{
    glBindBufferBase(GL_UNIFORM_BUFFER, SB_UBO_LIGHT_GRID, g->ubo[g->ring]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_LIGHT_GRID, g->cells_buf[g->ring]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_LIGHT_INDICES, g->index_buf[g->ring]);
}

/* The GPU's per-frame records, read once after the run. */
static void read_stats(struct light_grid *g)
{
    if (g->stats_read)
        return;
    g->stats_read = true;
    if (g->cfg.kind == LIGHT_GRID_TILES && g->cfg.binning == LIGHT_BINNING_CPU)
        return;
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->stats_buf);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0,
                       (GLsizeiptr)(((size_t)g->frames + 1) * sizeof(struct light_grid_stats)),
                       g->stats);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
}

bool light_grid_verify(struct light_grid *g, char *err, size_t errlen)
{
    read_stats(g);
    int first = 0, frames = 0;
    uint32_t cells = 0, dropped = 0, fullest = 0;
    for (int k = 1; k <= g->frames; k++) {
        const struct light_grid_stats *st = &g->stats[k];
        if (!st->overflow_cells)
            continue;
        if (!first)
            first = k;
        frames++;
        cells = st->overflow_cells > cells ? st->overflow_cells : cells;
        dropped = st->lights_dropped > dropped ? st->lights_dropped : dropped;
        fullest = st->fullest > fullest ? st->fullest : fullest;
    }
    if (!frames)
        return true;
    bool tiles = g->cfg.kind == LIGHT_GRID_TILES;
    LOG(LOG_WARN, "%s: light lists overflowed in %d of %d frames (up to %u cells, %u lights "
        "dropped a frame)%s", g->cfg.technique, frames, g->frames, cells, dropped,
        tiles || g->cfg.overflow == CLUSTER_OVERFLOW_FALLBACK
            ? "; those cells shaded with every light" : "");
    if (tiles || g->cfg.overflow == CLUSTER_OVERFLOW_FALLBACK)
        return true;
    snprintf(err, errlen,
             "%s.max_lights_per_cluster: light list overflow: from frame %d on (%d of %d "
             "frames) up to %u clusters held more than %d lights (the fullest %u; up to %u "
             "light entries dropped a frame); raise max_lights_per_cluster, use a finer grid, "
             "or set overflow to \"fallback\"",
             g->cfg.technique, first, frames, g->frames, cells, g->cfg.max_per_cell, fullest,
             dropped);
    return false;
}

static json_t *mean_max(const double *v, int n)
{
    double sum = 0, max = 0;
    for (int i = 0; i < n; i++) {
        sum += v[i];
        max = v[i] > max ? v[i] : max;
    }
    return json_pack("{s:f, s:f}", "mean", n ? sum / n : 0.0, "max", max);
}

json_t *light_grid_describe(struct light_grid *g)
{
    read_stats(g);
    bool tiles = g->cfg.kind == LIGHT_GRID_TILES;
    int n = g->frames;
    double *v = calloc((size_t)n + 1, sizeof(double));
    if (!v)
        return NULL;
    int overflow_frames = 0, first = 0;
    for (int k = 1; k <= n; k++)
        if (g->stats[k].overflow_cells && !overflow_frames++)
            first = k;
    json_t *out = json_object();
    json_t *grid = json_pack("{s:s, s:[i, i, i], s:i, s:[f, f]}", "kind",
                             tiles ? "tiles" : "clusters", "dims", g->block.dims[0],
                             g->block.dims[1], g->block.dims[2], "cells", g->cells, "tile_px",
                             g->block.tile[0], g->block.tile[1]);
    if (!tiles) {
        json_object_set_new(grid, "slices",
                            json_string(cluster_slices_choices[g->cfg.slices]));
        json_object_set_new(grid, "sliced_depth",
                            json_pack("[f, f]", g->block.slices[0], g->block.slices[1]));
    } else {
        json_object_set_new(grid, "depth_bounds",
                            json_string(g->cfg.binning == LIGHT_BINNING_CPU
                                            ? "none (CPU binning sees no depth buffer)"
                                            : "per tile, from the depth buffer"));
    }
    json_object_set_new(out, "grid", grid);
    json_object_set_new(out, "binning", json_string(light_binning_choices[g->cfg.binning]));
    json_object_set_new(
        out, "lists",
        json_pack("{s:o, s:I, s:s}", "max_per_cell",
                  tiles ? json_null() : json_integer(g->cfg.max_per_cell), "capacity",
                  (json_int_t)g->capacity, "overflow",
                  tiles ? "fallback" : cluster_overflow_choices[g->cfg.overflow]));
    for (int k = 1; k <= n; k++)
        v[k - 1] = g->stats[k].nonempty ? (double)g->stats[k].kept / g->stats[k].nonempty : 0;
    json_t *per_cell = mean_max(v, n);
    for (int k = 1; k <= n; k++)
        v[k - 1] = g->stats[k].fullest;
    json_object_set_new(per_cell, "fullest", mean_max(v, n));
    json_object_set_new(per_cell, "note",
                        json_string("mean: lights per non-empty cell; fullest: the longest "
                                    "list a frame needed (before any bound)"));
    json_object_set_new(out, "lights_per_cell", per_cell);
    json_t *ov = json_pack("{s:i, s:o}", RK_OVERFLOW_FRAMES, overflow_frames, "first_frame",
                           first ? json_integer(first) : json_null());
    for (int k = 1; k <= n; k++)
        v[k - 1] = g->stats[k].overflow_cells;
    json_object_set_new(ov, "cells_per_frame", mean_max(v, n));
    /* What happened: under fallback a cell whose list overflowed shades
     * with every light, so no light is dropped; what its list could not
     * hold is counted as unlisted entries. Under fail the job fails. */
    bool fallback = tiles || g->cfg.overflow == CLUSTER_OVERFLOW_FALLBACK;
    for (int k = 1; k <= n; k++)
        v[k - 1] = g->stats[k].lights_dropped;
    json_object_set_new(ov, "entries_unlisted_per_frame", mean_max(v, n));
    for (int k = 1; k <= n; k++)
        v[k - 1] = fallback ? 0.0 : g->stats[k].lights_dropped;
    json_object_set_new(ov, "lights_dropped_per_frame", mean_max(v, n));
    json_object_set_new(ov, "policy",
                        json_string(fallback ? "overflowed cells shade with every light: no "
                                               "light is dropped (cells_per_frame counts those "
                                               "cells, entries_unlisted_per_frame the list "
                                               "entries they could not hold)"
                                             : "the job fails"));
    json_object_set_new(out, RK_OVERFLOW, ov);
    struct stats st;
    stats_compute(g->bin_ms + 1, (size_t)n, &st);
    json_object_set_new(out, "binning_cpu_ms",
                        json_pack("{s:f, s:f, s:f, s:f, s:s}", "mean", st.mean, "median",
                                  st.median, "p95", st.p95, "max", st.max, "note",
                                  "CPU time of the binning pass's calls; on llvmpipe, which "
                                  "runs compute on the calling thread, this includes the "
                                  "binning work and any wait for the depth it reads"));
    json_object_set_new(out, "buffer_bytes", json_real(g->buffer_bytes));
    free(v);
    return out;
}
