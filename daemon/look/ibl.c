/* Image-based lighting: see ibl.h. The capture renders with forward
 * shading's program under PBR without image-based ambient (one bounce: the
 * probes see the scene lit by the point lights and the uniform ambient),
 * and without shadows. */
#define _POSIX_C_SOURCE 200809L
#include "daemon/look/ibl.h"

#include <epoxy/gl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/clock.h"
#include "daemon/gpu/bindings.h"
#include "daemon/gpu/glutil.h"
#include "daemon/lighting/cube_faces.h"
#include "daemon/lighting/ibl_plan.h"
#include "daemon/lighting/pbr_math.h"

enum {
    LUT_SIZE = 32,
    LUT_SAMPLES = 512,
    IRRADIANCE_SIZE = 16,
    IRRADIANCE_SAMPLES = 512,
    SMALLEST_LEVEL = 4, /* the roughest prefiltered level's edge */
};

/* shaders/common/ibl.glsl, IblBlock (std140). */
struct ibl_block {
    int32_t count[4];
    float probe[IBL_MAX_BLEND][4];
    int32_t layer[IBL_MAX_BLEND][4];
};

struct look_ibl {
    struct ibl_spec spec;
    const struct scene *scene;
    int probes;
    struct ibl_probe probe[IBL_MAX_PROBES];
    int levels, resolution;
    GLuint irradiance, prefiltered, brdf, ubo;
    struct ibl_block block;
    int selected[IBL_MAX_BLEND], nselected;
    bool bound_once;
    double bytes;
    double lut_ms, capture_ms, filter_ms, total_ms, gpu_capture_ms, gpu_filter_ms;
    int first_selected[IBL_MAX_BLEND], first_nselected;
};

static int log2i(int v)
{
    int l = 0;
    while ((1 << (l + 1)) <= v)
        l++;
    return l;
}

static GLuint cube_array(GLsizei levels, int size, int layers, bool mipmapped)
{
    GLuint t;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_CUBE_MAP_ARRAY, t);
    glTexStorage3D(GL_TEXTURE_CUBE_MAP_ARRAY, levels, GL_RGBA16F, size, size, 6 * layers);
    glTexParameteri(GL_TEXTURE_CUBE_MAP_ARRAY, GL_TEXTURE_MIN_FILTER,
                    mipmapped ? GL_LINEAR_MIPMAP_LINEAR : GL_LINEAR);
    glTexParameteri(GL_TEXTURE_CUBE_MAP_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_CUBE_MAP_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_CUBE_MAP_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return t;
}

/* The GPU work of one phase, timed by a query and by the wall clock around
 * a glFinish (on llvmpipe the query misses vertex work). */
struct phase {
    GLuint query;
    double t0;
};

static void phase_begin(struct phase *p)
{
    glFinish();
    p->t0 = clock_mono_s();
    glBeginQuery(GL_TIME_ELAPSED, p->query);
}

static void phase_end(struct phase *p, double *wall_ms, double *gpu_ms)
{
    glEndQuery(GL_TIME_ELAPSED);
    glFinish();
    *wall_ms += (clock_mono_s() - p->t0) * 1e3;
    GLuint64 ns = 0;
    glGetQueryObjectui64v(p->query, GL_QUERY_RESULT, &ns);
    *gpu_ms += (double)ns / 1e6;
}

struct filters {
    GLuint capture_prog, irradiance_prog, prefilter_prog, vao, fbo, source, depth;
    struct scene_program capture;
};

static void filters_finish(struct filters *f)
{
    glDeleteProgram(f->capture_prog);
    glDeleteProgram(f->irradiance_prog);
    glDeleteProgram(f->prefilter_prog);
    glDeleteVertexArrays(1, &f->vao);
    glDeleteFramebuffers(1, &f->fbo);
    glDeleteTextures(1, &f->source);
    glDeleteRenderbuffers(1, &f->depth);
}

static bool filters_init(struct filters *f, struct look_ibl *ibl, const struct gpu_scene *gpu,
                         char *err, size_t errlen)
{
    memset(f, 0, sizeof(*f));
    char defines[192];
    snprintf(defines, sizeof(defines), "#define LIGHTING_PBR 1\n#define PBR_MIN_ROUGHNESS %.9g\n",
             PBR_MIN_ROUGHNESS);
    const struct gl_stage capture[] = {{GL_VERTEX_SHADER, {"scene.vert"}},
                                       {GL_FRAGMENT_SHADER, {"forward.frag"}}};
    const struct gl_stage irradiance[] = {{GL_VERTEX_SHADER, {"fullscreen.vert"}},
                                          {GL_FRAGMENT_SHADER, {"ibl_irradiance.frag"}}};
    const struct gl_stage prefilter[] = {{GL_VERTEX_SHADER, {"fullscreen.vert"}},
                                         {GL_FRAGMENT_SHADER, {"ibl_prefilter.frag"}}};
    if (!(f->capture_prog = gl_program_build("ibl capture", capture, 2, defines, err, errlen)) ||
        !(f->irradiance_prog =
              gl_program_build("ibl irradiance", irradiance, 2, defines, err, errlen)) ||
        !(f->prefilter_prog = gl_program_build("ibl prefilter", prefilter, 2, defines, err, errlen)))
        return false;
    f->capture = gpu_scene_program(gpu, f->capture_prog);
    glGenVertexArrays(1, &f->vao);
    glGenFramebuffers(1, &f->fbo);
    int res = ibl->resolution;
    glGenTextures(1, &f->source);
    glBindTexture(GL_TEXTURE_CUBE_MAP, f->source);
    glTexStorage2D(GL_TEXTURE_CUBE_MAP, log2i(res) + 1, GL_RGBA16F, res, res);
    glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glGenRenderbuffers(1, &f->depth);
    glBindRenderbuffer(GL_RENDERBUFFER, f->depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, res, res);
    return true;
}

/* Layer `layer`'s source: the environment alone (probe NULL) or the scene
 * from the probe, into the source cube map with its mip chain. */
static bool capture(struct look_ibl *ibl, struct filters *f, const struct look_ibl_env *env,
                    const struct ibl_probe *probe, struct gpu_budget *budget)
{
    const struct scene *s = env->scene;
    int res = ibl->resolution;
    float pos[3] = {0, 0, 0};
    if (probe)
        memcpy(pos, probe->pos, sizeof(pos));
    const struct scene_box *b = &s->bounds;
    float diag = sqrtf(powf(b->max[0] - b->min[0], 2) + powf(b->max[1] - b->min[1], 2) +
                       powf(b->max[2] - b->min[2], 2));
    glBindFramebuffer(GL_FRAMEBUFFER, f->fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, f->depth);
    glViewport(0, 0, res, res);
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_BLEND);
    gpu_loop_begin(budget);
    for (int face = 0; face < 6 && !gpu_budget_stopped(budget); face++) {
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0,
                               GL_TEXTURE_CUBE_MAP_POSITIVE_X + (GLenum)face, f->source, 0);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            return false;
        glClearColor(0, 0, 0, 1);
        glDepthMask(GL_TRUE);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        struct gpu_frame_data fd;
        memset(&fd, 0, sizeof(fd));
        float near_z = 0.05f, far_z = fmaxf(2.0f * diag, 10.0f);
        cube_face_view_proj(face, pos, 1.0f, near_z, far_z, fd.view_proj);
        memcpy(fd.view, fd.view_proj, sizeof(fd.view));
        mat4_invert(fd.view_proj, fd.inv_view_proj);
        memcpy(fd.inv_view, fd.inv_view_proj, sizeof(fd.inv_view));
        fd.eye[0] = pos[0], fd.eye[1] = pos[1], fd.eye[2] = pos[2], fd.eye[3] = 1.0f;
        fd.viewport[0] = fd.viewport[1] = (float)res;
        fd.viewport[2] = fd.viewport[3] = 1.0f / (float)res;
        fd.clip[0] = near_z, fd.clip[1] = far_z;
        fd.counts[0] = 1;
        fd.counts[1] = s->light_count;
        fd.counts[2] = s->instance_count;
        gpu_frame_block_update(env->frame_block, &fd);
        /* A face of a probe among many lights can take seconds: in tiles
         * (bounded submissions, daemon/gpu/budget.h). */
        struct gpu_tiles t;
        for (gpu_tiles_begin(budget, res, res, &t); gpu_tiles_next(budget, &t);) {
            if (probe) {
                /* The cube's faces are rotations, but draw both sides
                 * anyway: a probe may stand where back faces show (the
                 * teapot's rim). */
                glEnable(GL_DEPTH_TEST);
                glDepthFunc(GL_LESS);
                glDisable(GL_CULL_FACE);
                gpu_scene_bind(env->gpu, &f->capture);
                gpu_scene_draw(env->gpu, &f->capture);
            }
            glEnable(GL_DEPTH_TEST);
            look_sky_draw(env->sky);
        }
        gpu_loop_step(budget);
    }
    gpu_loop_end(budget);
    if (gpu_budget_stopped(budget))
        return false;
    glBindTexture(GL_TEXTURE_CUBE_MAP, f->source);
    glGenerateMipmap(GL_TEXTURE_CUBE_MAP);
    return true;
}

/* A face of a filtered map: samples x texels can take long, so in tiles. */
static void draw_face(struct filters *f, GLuint target, int level, int layer_face, int size,
                      struct gpu_budget *b)
{
    glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, target, level, layer_face);
    glViewport(0, 0, size, size);
    glBindVertexArray(f->vao);
    struct gpu_tiles t;
    for (gpu_tiles_begin(b, size, size, &t); gpu_tiles_next(b, &t);)
        glDrawArrays(GL_TRIANGLES, 0, 3);
}

static bool filter(struct look_ibl *ibl, struct filters *f, int layer, struct gpu_budget *b)
{
    int res = ibl->resolution;
    glBindFramebuffer(GL_FRAMEBUFFER, f->fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, 0);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_IBL_SOURCE);
    glBindTexture(GL_TEXTURE_CUBE_MAP, f->source);
    glActiveTexture(GL_TEXTURE0);
    /* Irradiance: from the level with about 8 x 8 texels a face. */
    glUseProgram(f->irradiance_prog);
    float lod = (float)(log2i(res) > 3 ? log2i(res) - 3 : 0);
    glUniform4f(SB_LOC_IBL_PARAMS, lod, 1.0f / IRRADIANCE_SIZE, (float)IRRADIANCE_SAMPLES,
                (float)res);
    for (int face = 0; face < 6; face++) {
        glUniform1i(SB_LOC_IBL_FACE, face);
        draw_face(f, ibl->irradiance, 0, layer * 6 + face, IRRADIANCE_SIZE, b);
    }
    /* Prefiltered: level l at roughness l / (levels - 1). */
    glUseProgram(f->prefilter_prog);
    for (int l = 0; l < ibl->levels; l++) {
        int size = res >> l;
        float roughness = ibl->levels > 1 ? (float)l / (float)(ibl->levels - 1) : 0.0f;
        glUniform4f(SB_LOC_IBL_PARAMS, roughness, 1.0f / (float)size, (float)ibl->spec.samples,
                    (float)res);
        for (int face = 0; face < 6; face++) {
            glUniform1i(SB_LOC_IBL_FACE, face);
            draw_face(f, ibl->prefiltered, l, layer * 6 + face, size, b);
        }
    }
    glBindVertexArray(0);
    return !gpu_budget_stopped(b) &&
           glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
}

struct look_ibl *look_ibl_create(const struct look_ibl_env *env, char *err, size_t errlen)
{
    struct look_ibl *ibl = calloc(1, sizeof(*ibl));
    float *table = malloc(LUT_SIZE * LUT_SIZE * 2 * sizeof(float));
    struct filters f;
    struct phase phase = {0};
    memset(&f, 0, sizeof(f));
    bool ok = false;
    if (!ibl || !table) {
        snprintf(err, errlen, "look.ibl: out of memory");
        goto out;
    }
    double t_start = clock_mono_s();
    ibl->spec = *env->spec;
    ibl->scene = env->scene;
    ibl->probes = env->spec->probes;
    ibl->resolution = env->spec->resolution;
    ibl->levels = log2i(ibl->resolution) - log2i(SMALLEST_LEVEL) + 1;
    if (ibl->levels < 1)
        ibl->levels = 1;
    ibl_place_probes(env->scene, env->spec, ibl->probe);

    /* The split sum's table, integrated on the CPU (the unit tests check
     * the same function). */
    double t0 = clock_mono_s();
    pbr_env_brdf_table(LUT_SIZE, LUT_SAMPLES, table);
    ibl->lut_ms = (clock_mono_s() - t0) * 1e3;
    glGenTextures(1, &ibl->brdf);
    glBindTexture(GL_TEXTURE_2D, ibl->brdf);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_RG32F, LUT_SIZE, LUT_SIZE);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, LUT_SIZE, LUT_SIZE, GL_RG, GL_FLOAT, table);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);

    int layers = 1 + ibl->probes;
    ibl->irradiance = cube_array(1, IRRADIANCE_SIZE, layers, false);
    ibl->prefiltered = cube_array(ibl->levels, ibl->resolution, layers, true);
    double level_texels = 0;
    for (int l = 0; l < ibl->levels; l++)
        level_texels += (double)(ibl->resolution >> l) * (ibl->resolution >> l);
    ibl->bytes = 6.0 * layers * 8.0 * (level_texels + IRRADIANCE_SIZE * IRRADIANCE_SIZE) +
                 LUT_SIZE * LUT_SIZE * 8.0;
    glGenBuffers(1, &ibl->ubo);
    glBindBuffer(GL_UNIFORM_BUFFER, ibl->ubo);
    glBufferData(GL_UNIFORM_BUFFER, sizeof(struct ibl_block), NULL, GL_DYNAMIC_DRAW);
    glBindBuffer(GL_UNIFORM_BUFFER, 0);
    glEnable(GL_TEXTURE_CUBE_MAP_SEAMLESS);
    if (!filters_init(&f, ibl, env->gpu, err, errlen))
        goto out;

    /* Lights as they stand at the first timed frame. */
    int64_t first = 1;
    gpu_scene_set_light_rows(env->gpu, &first, 1);
    glGenQueries(1, &phase.query);
    /* The set-up's pieces are measured apart from the frames'. */
    struct gpu_budget budget;
    gpu_budget_init(&budget, env->budget ? env->budget->stop : NULL,
                    env->budget ? env->budget->ctx : NULL);
    budget.progress = env->budget ? env->budget->progress : NULL;
    for (int layer = 0; layer < layers; layer++) {
        /* Each probe draws the same pieces: measured once (the first
         * probe: the environment before it draws no scene), drawn by that
         * measure after. */
        gpu_budget_frame(&budget);
        if (layer == 1)
            gpu_budget_forget(&budget);
        phase_begin(&phase);
        bool captured = capture(ibl, &f, env, layer ? &ibl->probe[layer - 1] : NULL, &budget);
        phase_end(&phase, &ibl->capture_ms, &ibl->gpu_capture_ms);
        phase_begin(&phase);
        bool filtered = captured && filter(ibl, &f, layer, &budget);
        phase_end(&phase, &ibl->filter_ms, &ibl->gpu_filter_ms);
        if (!filtered) {
            if (gpu_budget_stopped(&budget))
                snprintf(err, errlen, "stopped while look.ibl captured and filtered probe %d of %d",
                         layer, layers - 1);
            else
                snprintf(err, errlen, "look.ibl: the capture framebuffer is incomplete");
            goto out;
        }
    }
    ibl->total_ms = (clock_mono_s() - t_start) * 1e3;
    /* The choice at frame 1, for the result. */
    look_ibl_frame(ibl, 1);
    memcpy(ibl->first_selected, ibl->selected, sizeof(ibl->selected));
    ibl->first_nselected = ibl->nselected;
    ok = true;
out:
    if (phase.query)
        glDeleteQueries(1, &phase.query);
    filters_finish(&f);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    free(table);
    if (!ok) {
        look_ibl_destroy(ibl);
        return NULL;
    }
    return ibl;
}

void look_ibl_frame(struct look_ibl *ibl, int64_t frame)
{
    const struct scene *s = ibl->scene;
    if (!ibl->bound_once || scene_camera_moves(s)) {
        struct scene_camera cam;
        scene_camera_at(s, frame, &cam);
        int pick[IBL_MAX_BLEND];
        int n = ibl_select(ibl->probe, ibl->probes, cam.eye, ibl->spec.blend, pick);
        if (!ibl->bound_once || n != ibl->nselected ||
            memcmp(pick, ibl->selected, (size_t)n * sizeof(int)) != 0) {
            memset(&ibl->block, 0, sizeof(ibl->block));
            ibl->block.count[0] = n;
            ibl->block.count[1] = ibl->levels - 1;
            for (int i = 0; i < n; i++) {
                const struct ibl_probe *p = &ibl->probe[pick[i]];
                memcpy(ibl->block.probe[i], p->pos, sizeof(p->pos));
                ibl->block.probe[i][3] = p->radius;
                ibl->block.layer[i][0] = pick[i] + 1;
            }
            memcpy(ibl->selected, pick, sizeof(pick));
            ibl->nselected = n;
            glBindBuffer(GL_UNIFORM_BUFFER, ibl->ubo);
            glBufferSubData(GL_UNIFORM_BUFFER, 0, sizeof(ibl->block), &ibl->block);
            glBindBuffer(GL_UNIFORM_BUFFER, 0);
        }
        ibl->bound_once = true;
    }
    glBindBufferBase(GL_UNIFORM_BUFFER, SB_UBO_IBL, ibl->ubo);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_IBL_IRRADIANCE);
    glBindTexture(GL_TEXTURE_CUBE_MAP_ARRAY, ibl->irradiance);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_IBL_PREFILTERED);
    glBindTexture(GL_TEXTURE_CUBE_MAP_ARRAY, ibl->prefiltered);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_IBL_BRDF);
    glBindTexture(GL_TEXTURE_2D, ibl->brdf);
    glActiveTexture(GL_TEXTURE0);
}

json_t *look_ibl_describe(const struct look_ibl *ibl)
{
    json_t *probes = json_array(), *chosen = json_array();
    for (int i = 0; i < ibl->probes; i++)
        json_array_append_new(probes, json_pack("{s:[f, f, f], s:f}", "position",
                                                (double)ibl->probe[i].pos[0],
                                                (double)ibl->probe[i].pos[1],
                                                (double)ibl->probe[i].pos[2], "radius",
                                                (double)ibl->probe[i].radius));
    for (int i = 0; i < ibl->first_nselected; i++)
        json_array_append_new(chosen, json_integer(ibl->first_selected[i]));
    return json_pack(
        "{s:s, s:f, s:o, s:s, s:i, s:i, s:i, s:i, s:i, s:o, s:{s:i, s:i}, s:f, "
        "s:{s:f, s:f, s:f, s:f}, s:{s:f, s:f}, s:s}",
        "environment",
        ibl->spec.environment == IBL_ENV_ASSET ? ibl->spec.env_asset
                                               : ibl_environment_names[ibl->spec.environment],
        "intensity",
        ibl->spec.intensity, "probes", probes, "placement", ibl->spec.placed ? "given" : "auto",
        "resolution", ibl->resolution, "prefiltered_levels", ibl->levels, "irradiance_size",
        IRRADIANCE_SIZE, "samples", ibl->spec.samples, "blend", ibl->spec.blend,
        "blended_at_frame_1", chosen, "brdf_table", "size", LUT_SIZE, "samples", LUT_SAMPLES,
        "bytes", ibl->bytes, "setup_ms", "brdf_table", ibl->lut_ms, "capture", ibl->capture_ms,
        "filter", ibl->filter_ms, "total", ibl->total_ms, "setup_gpu_ms", "capture",
        ibl->gpu_capture_ms, "filter", ibl->gpu_filter_ms, "timing",
        "setup_ms: wall time of each phase between glFinish calls, before the warm-up frames "
        "(the first draws include the driver's shader compilation); setup_gpu_ms: "
        "GL_TIME_ELAPSED around the same phases, which llvmpipe does not measure reliably");
}

void look_ibl_destroy(struct look_ibl *ibl)
{
    if (!ibl)
        return;
    glDeleteTextures(1, &ibl->irradiance);
    glDeleteTextures(1, &ibl->prefiltered);
    glDeleteTextures(1, &ibl->brdf);
    glDeleteBuffers(1, &ibl->ubo);
    free(ibl);
}
