/* OSL's visibility "seen": the blocks the raster pass read, selected and
 * shaded on the GPU (osl_gl.h, osl_select.comp). */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/gpu/glutil.h"
#include "common/log.h"
#include "daemon/gpu/bindings.h"
#include "daemon/techniques/osl/osl_gl.h"

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
bool osl_seen_create(struct osl *o, const struct technique_env *env, char *err, size_t errlen)
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
    /* Each block's instance, with the level it lies in above bit 24. */
    for (int i = 0; i < n; i++)
        for (int l = 0; l < osl_tile_levels(o->tiles[i].size, o->levels); l++) {
            int ox, oy, size = o->tiles[i].size >> l;
            osl_level_origin(l, o->atlas_w, o->atlas_h0, &ox, &oy);
            ox += o->tiles[i].x >> l;
            oy += o->tiles[i].y >> l;
            for (int y = oy / 8; y < (oy + size) / 8; y++)
                for (int x = ox / 8; x < (ox + size) / 8; x++)
                    owner[(size_t)y * (size_t)o->blocks_x + (size_t)x] = (GLuint)i | (GLuint)l << 24;
        }
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
    snprintf(mark_defines, sizeof(mark_defines), "#define OSL_SEEN 1\n%s%s%s%s",
             o->prepass ? "#define OSL_MARK_ONLY 1\n" : "",
             o->levels > 1 ? "#define OSL_LEVELS 1\n" : "", o->split ? "#define OSL_SPLIT 1\n" : "",
             env->scene->asset ? env->defines : "");
    GLuint mark_prog = gl_program_build(o->prepass ? "osl marks" : "osl draw (marking)", draw, 2,
                                        mark_defines, err, errlen);
    if (!mark_prog)
        return false;
    o->draw_mark = gpu_scene_program(env->gpu, mark_prog);
    osl_set_draw_uniforms(o, mark_prog);
    o->draw_frame_loc = glGetUniformLocation(mark_prog, "u_frame_index");
    o->sel_seen_since_loc = glGetUniformLocation(sp, "u_seen_since");
    o->sel_margin_loc = glGetUniformLocation(sp, "u_margin");
    glProgramUniform1i(sp, o->sel_margin_loc, OSL_SEEN_MARGIN(o));
    o->sel_budget_loc = glGetUniformLocation(sp, "u_budget");
    glProgramUniform1i(sp, o->sel_budget_loc, o->budget_blocks);
    return true;
}

void osl_seen_bind(const struct osl *o)
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
void osl_seen_light_pass(struct osl *o, const struct technique_env *env, int64_t frame,
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
    osl_seen_bind(o);
    glUseProgram(o->select_prog);
    glUniform1i(o->sel_frame_loc, (GLint)frame);
    /* With no marks yet every block is shaded once, unless a marking pass
     * of this frame's camera ran. */
    glUniform1i(o->sel_initial_loc, initial && !o->prepass);
    glUniform1i(o->sel_count_loc, count);
    /* The frame before counts when it was a timed frame rendered just before. */
    glUniform1i(o->sel_count_prev_loc, !initial && o->last_counted && o->last_frame == frame - 1);
    o->last_counted = false;
    glUniform1i(o->sel_mode_loc, 0);
    /* A still camera sees the same blocks every frame: the first frame's
     * marks stand for all; a moving one marked this frame's. */
    glUniform1i(o->sel_seen_since_loc, o->prepass ? (GLint)frame : INT_MIN + 1);
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

    osl_bind_light_inputs(o, env);
    osl_seen_bind(o);
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, o->stats_buf);
    /* Whole in timed frames; in ranges where the harness slices (the
     * first shading of every seen block, in the measuring frame). */
    gpu_dispatch_indirect(env->budget, 0, o->group_base_loc, o->group_end_loc, o->groups_x_max);
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
}

/* Objects with a block read (the marks hold the last frame each block was
 * read: with a still camera, the first frame's reads), and objects with a
 * block shaded in a timed frame, and objects shaded in a timed frame with
 * no block read. Read back once, after the run. */
void osl_seen_objects(const struct osl *o, int out[3], long read_by_level[16])
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
    for (int l = 0; l < 16; l++)
        read_by_level[l] = 0;
    for (size_t b = 0; b < blocks; b++) {
        GLuint inst = owner[b] & 0xffffffu, level = owner[b] >> 24;
        if (owner[b] == 0xffffffffu || inst >= (GLuint)n)
            continue;
        /* The last frame's reads (a still camera's marks stand for all). */
        if (marks[b] != INT_MIN && (!o->prepass || marks[b] == (GLint)o->last_frame))
            read_by_level[level & 15]++;
        if (marks[b] != INT_MIN)
            flags[inst] |= 1;
        if (shaded[b * 8 + 3] >= 1 && shaded[b * 8 + 3] <= o->frames)
            flags[inst] |= 2;
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

void osl_seen_count_reads(struct osl *o, int64_t frame)
{
    bool prev = o->last_counted && o->last_frame == frame - 1;
    o->last_counted = false;
    if (!prev)
        return;
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    osl_seen_bind(o);
    glUseProgram(o->select_prog);
    glUniform1i(o->sel_frame_loc, (GLint)frame);
    glUniform1i(o->sel_count_prev_loc, 1);
    glUniform1i(o->sel_mode_loc, 2);
    glUniform1i(o->sel_seen_since_loc, o->prepass ? (GLint)(frame - 1) : INT_MIN + 1);
    glDispatchCompute(((GLuint)o->blocks_x * (GLuint)o->blocks_y + 63) / 64, 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
}
