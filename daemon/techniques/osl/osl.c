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
#include "daemon/techniques/osl/osl_gl.h"

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
        for (int l = 0; l < osl_tile_levels(o->tiles[i].size, o->levels); l++)
            blocks += (double)((o->tiles[i].size >> l) / 8) * ((o->tiles[i].size >> l) / 8);
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
     * 0.9965 at two, 0.9993 at four: the lights preset, 160x120); 0.5
     * (a quarter of a texel a pixel by area at the finest level read) where
     * the base colour and the normal are applied per pixel (split), since
     * the light alone is smooth: the showcase court with 64 moving lights
     * at 480x360 gives SSIM 0.99982 at 0.5 (0.785 of forward's frame
     * time) and 0.99986 at 0.71 (1.35: glTF's lights reach the whole
     * court, so culling per block keeps them all), and with 8 lights at
     * 160x120 0.99934 at 0.35, 0.99959 at 0.5, 0.99973 at 0.71. */
    double density = opt->texel_density;
    if (density == 0)
        density = env->look->lighting == LOOK_PBR ? 2.0 : o->split ? 0.5 : 1.0;
    o->density = density;
    int largest = 8;
    for (int i = 0; i < n; i++) {
        if (opt->resolution) {
            sizes[i] = opt->resolution;
            continue;
        }
        double r = scene_instance_bound(s, i);
        double ppu = scene_projected_diameter(s, i) / (2.0 * r);
        if (o->levels > 1) {
            /* Level 0 for the object's nearest point (its bound's), the
             * coarser levels for what the raster pass finds farther: a
             * ground that spans near and far gets each at its density. */
            double dist = scene_instance_distance(s, i);
            ppu *= dist / fmax(dist - r, 0.05 * dist);
            /* Twice as fine again: the nearest power of two may be 0.7 of
             * what a face seen head-on needs, and the levels cost memory,
             * not shading (the raster pass reads the level it needs). */
            ppu *= 2.0;
        }
        const struct mesh *m = &s->meshes[s->instances[i].mesh];
        sizes[i] = osl_auto_tile_size(ppu, m->uv_per_unit / s->instances[i].scale, density);
        if (sizes[i] > largest)
            largest = sizes[i];
    }
    if (o->levels > 1)
        o->levels = osl_tile_levels(largest, 16);
    /* The packer counts 4 bytes a texel; an HDR atlas takes 8, and the
     * coarser levels half as much again. */
    double stack = o->levels > 1 ? 1.5 : 1.0;
    bool ok = osl_atlas_pack(sizes, n, max_tex,
                             OSL_MAX_ATLAS_BYTES / (o->textured ? 2.0 : 1.0) / stack, o->tiles,
                             &o->atlas_w, &o->atlas_h0, err, errlen);
    o->atlas_h = o->levels > 1 ? o->atlas_h0 + o->atlas_h0 / 2 : o->atlas_h0;
    if (ok && o->atlas_h > max_tex) {
        snprintf(err, errlen, "the shading atlas and its levels need %dx%d texels; this device "
                 "allows at most %dx%d: lower osl.texel_density", o->atlas_w, o->atlas_h,
                 max_tex, max_tex);
        ok = false;
    }
    free(sizes);
    return ok;
}

/* The lighting pass's program and inputs, whichever way it finds its blocks:
 * the tiles, the atlas to write, each mesh's position and normal textures. */
void osl_bind_light_inputs(const struct osl *o, const struct technique_env *env)
{
    gpu_scene_bind(env->gpu, &o->light);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_OSL_TILES, o->tile_buffer);
    glBindImageTexture(SB_IMG_OSL_ATLAS, o->atlas, 0, GL_FALSE, 0, GL_WRITE_ONLY,
                       OSL_ATLAS_FORMAT(o));
    if (o->split)
        glBindImageTexture(SB_IMG_OSL_ATLAS_SPECULAR, o->atlas_specular, 0, GL_FALSE, 0,
                           GL_WRITE_ONLY, OSL_ATLAS_FORMAT(o));
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
    o->work = calloc((size_t)n * 4 * 16, sizeof(GLuint)); /* an entry per level */
    o->frames = env->frames;
    o->env = env;
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
    /* Auto tiles get levels, picked per pixel by the raster pass; a fixed
     * resolution (the thesis's 256) is one level, as the thesis drew it. */
    o->levels = opt->resolution ? 1 : 2;
    o->split = o->textured && env->look->lighting != LOOK_PBR;
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
    o->prepass = o->seen && o->camera_moves;
    /* Whole blocks: a budget under one block still shades what must be. */
    o->budget_blocks = opt->budget_texels > 0 ? opt->budget_texels / 64 : -1;
    o->light_rows = o->schedule.max_period > 0 ? o->schedule.max_period : 1;
    if (o->seen && opt->change_threshold > 0) {
        if (env->look->lighting == LOOK_PBR)
            o->change_why = "the bound covers Phong and Blinn-Phong, not PBR's BRDF";
        else {
            o->change_on = true;
            /* Phong's motion bound; Blinn-Phong's half vector and shadows'
             * visibility have none, so only the range bound holds there. */
            o->change_lipschitz =
                env->look->lighting == LOOK_PHONG && !env->look->shadows.enabled;
            o->light_rows += OSL_CHANGE_ROWS;
            o->anchor = malloc((size_t)n * sizeof(int64_t));
            if (!o->anchor)
                goto oom;
            for (int i = 0; i < n; i++)
                o->anchor[i] = INT64_MIN;
        }
    }
    char light_defines[2048];
    snprintf(light_defines, sizeof(light_defines), "%s%s%s%s", env->defines ? env->defines : "",
             o->seen ? "#define OSL_BLOCK_LIST 1\n" : "", o->split ? "#define OSL_SPLIT 1\n" : "",
             o->levels > 1 ? "#define OSL_CULL 1\n" : "");
    /* Asset scenes bake their materials in texture generation and cut the
     * mask's holes in the raster pass, both through surface.glsl: those
     * programs take the scene's defines (SCENE_TEXTURED) there only, so the
     * procedural scenes' programs stay the text they always were. */
    const char *scene_defines = s->asset ? env->defines : NULL;
    char draw_defines[2048];
    snprintf(draw_defines, sizeof(draw_defines), "%s%s%s",
             o->levels > 1 ? "#define OSL_LEVELS 1\n" : "", o->split ? "#define OSL_SPLIT 1\n" : "",
             scene_defines ? scene_defines : "");
    if (!(o->texgen_prog = gl_program_build("osl texgen", texgen, 2, scene_defines, err, errlen)) ||
        !(light_prog = gl_program_build("osl lighting", light, 1, light_defines, err, errlen)) ||
        !(draw_prog = gl_program_build("osl draw", draw, 2,
                                       draw_defines[0] ? draw_defines : NULL, err, errlen))) {
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
    glProgramUniform1i(light_prog, glGetUniformLocation(light_prog, "u_atlas_h0"), o->atlas_h0);
    glProgramUniform1i(light_prog, glGetUniformLocation(light_prog, "u_atlas_w"), o->atlas_w);

    if (!osl_generate_textures(o, env, err, errlen))
        goto fail;
    glGenTextures(1, &o->atlas);
    glBindTexture(GL_TEXTURE_2D, o->atlas);
    glTexStorage2D(GL_TEXTURE_2D, 1, OSL_ATLAS_FORMAT(o), o->atlas_w, o->atlas_h);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    if (o->split) {
        glGenTextures(1, &o->atlas_specular);
        glBindTexture(GL_TEXTURE_2D, o->atlas_specular);
        glTexStorage2D(GL_TEXTURE_2D, 1, OSL_ATLAS_FORMAT(o), o->atlas_w, o->atlas_h);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    }
    osl_set_draw_uniforms(o, o->draw.prog);
    glProgramUniform2i(light_prog, glGetUniformLocation(light_prog, "u_geo_size0"), o->geo_w,
                       o->geo_h0);

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
    glBufferData(GL_SHADER_STORAGE_BUFFER,
                 (GLsizeiptr)((size_t)n * (size_t)o->levels * 4 * sizeof(GLuint)), NULL,
                 GL_STREAM_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    if (o->seen && !osl_seen_create(o, env, err, errlen))
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
    int rows = 1, entries = 0;
    uint32_t blocks = 0;
    double texels = 0;
    for (int k = 0; k < count; k++) {
        int i = o->plan[k].instance;
        int row = (int)(frame - o->plan[k].time);
        if (row + 1 > rows)
            rows = row + 1;
        /* One entry per level: the instance with its level above bit 24. */
        for (int l = 0; l < osl_tile_levels(o->tiles[i].size, o->levels); l++) {
            int per_row = (o->tiles[i].size >> l) / 8;
            GLuint *w = &o->work[(size_t)entries++ * 4];
            w[0] = (GLuint)i | (GLuint)l << 24;
            w[1] = (GLuint)row;
            w[2] = blocks;
            w[3] = (GLuint)per_row;
            blocks += (uint32_t)(per_row * per_row);
            texels += 64.0 * per_row * per_row;
        }
    }
    count = entries;
    for (int r = 0; r < rows; r++)
        o->rows[r] = frame - r;
    gpu_scene_set_light_rows(env->gpu, o->rows, rows);

    glBindBuffer(GL_SHADER_STORAGE_BUFFER, o->work_buffer);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((size_t)count * 4 * sizeof(GLuint)),
                 o->work, GL_STREAM_DRAW);
    osl_bind_light_inputs(o, env);
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

void osl_set_draw_uniforms(const struct osl *o, GLuint prog)
{
    glProgramUniform1i(prog, glGetUniformLocation(prog, "u_atlas"), SB_TEX_OSL_ATLAS);
    glProgramUniform1i(prog, glGetUniformLocation(prog, "u_atlas_specular"),
                       SB_TEX_OSL_ATLAS_SPECULAR);
    glProgramUniform2f(prog, glGetUniformLocation(prog, "u_atlas_size"), (float)o->atlas_w,
                       (float)o->atlas_h);
    glProgramUniform2i(prog, glGetUniformLocation(prog, "u_atlas_size0"), o->atlas_w, o->atlas_h0);
    glProgramUniform1f(prog, glGetUniformLocation(prog, "u_density"), (float)o->density);
}

/* The shading atlas (and its specular plane) for the raster pass. */
static void bind_atlas(const struct osl *o)
{
    if (o->split) {
        glActiveTexture(GL_TEXTURE0 + SB_TEX_OSL_ATLAS_SPECULAR);
        glBindTexture(GL_TEXTURE_2D, o->atlas_specular);
    }
    glActiveTexture(GL_TEXTURE0 + SB_TEX_OSL_ATLAS);
    glBindTexture(GL_TEXTURE_2D, o->atlas);
}

/* A moving camera's marks: every object drawn with this frame's camera,
 * depth and marks only (osl_draw.frag with OSL_MARK_ONLY), before the
 * selection reads them. Its cost is counted in the lighting pass. */
static void mark_pass(struct osl *o, const struct technique_env *env, int64_t frame)
{
    gpu_pass_begin(env->passes, PASS_LIGHTING, env->output_fbo, env->width, env->height);
    glClear(GL_DEPTH_BUFFER_BIT);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    gpu_scene_bind(env->gpu, &o->draw_mark);
    glUniform1i(o->draw_frame_loc, (GLint)frame);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_OSL_TILES, o->tile_buffer);
    osl_seen_bind(o);
    struct gpu_tiles t;
    for (gpu_tiles_begin(env->budget, env->width, env->height, &t); gpu_tiles_next(env->budget, &t);)
        gpu_scene_draw(env->gpu, &o->draw_mark);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gpu_pass_end(env->passes);
}

static bool osl_render(void *state, const struct technique_env *env, int64_t frame,
                       char *err, size_t errlen)
{
    struct osl *o = state;
    if (o->seen) {
        o->pixels = (double)env->width * env->height;
        bool counted = frame >= 1 && frame <= o->frames;
        if (o->prepass) {
            osl_seen_count_reads(o, frame);
            mark_pass(o, env, frame);
        }
        osl_seen_light_pass(o, env, frame, !o->shaded_once, counted);
        o->timed_frames += counted;
        o->shaded_once = true;
        gpu_pass_begin(env->passes, PASS_RASTER, env->output_fbo, env->width, env->height);
        glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        bool mark = !o->prepass && !o->marked_once;
        const struct scene_program *draw = mark ? &o->draw_mark : &o->draw;
        gpu_scene_bind(env->gpu, draw);
        if (mark)
            glUniform1i(o->draw_frame_loc, (GLint)frame);
        o->marked_once = true;
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_OSL_TILES, o->tile_buffer);
        osl_seen_bind(o);
        o->last_frame = frame;
        o->last_counted = counted; /* a still camera reads its first marks every frame */
        bind_atlas(o);
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
    bind_atlas(o);
    struct gpu_tiles t;
    for (gpu_tiles_begin(env->budget, env->width, env->height, &t); gpu_tiles_next(env->budget, &t);)
        gpu_scene_draw(env->gpu, &o->draw);
    gpu_pass_end(env->passes);
    return technique_keep_going(env, err, errlen);
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
    glDeleteTextures(1, &o->atlas_specular);
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
