#include "daemon/techniques/shared/gbuffer.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/gpu/bindings.h"
#include "daemon/gpu/glutil.h"

static const char *const normal_defines[] = {
    "#define GBUFFER_NORMAL_OCTAHEDRAL 1\n",
    "#define GBUFFER_NORMAL_FLOAT3 1\n",
    "#define GBUFFER_NORMAL_XY_RECONSTRUCT_Z 1\n",
};
static const char *const albedo_defines[] = {
    "#define GBUFFER_ALBEDO_RGBA8 1\n",
    "#define GBUFFER_ALBEDO_PACK_SHIFT 1\n",
    "#define GBUFFER_ALBEDO_PACK_BASE10 1\n",
};

static bool renderable(GLenum format)
{
    GLint support = GL_NONE;
    glGetInternalformativ(GL_TEXTURE_2D, format, GL_FRAMEBUFFER_RENDERABLE, 1, &support);
    return support == GL_FULL_SUPPORT;
}

static double format_bytes(GLenum f)
{
    switch (f) {
    case GL_RGBA32F:
        return 16;
    case GL_RG32F:
        return 8;
    default:
        return 4; /* RGBA8, R32F, RG16_SNORM */
    }
}

static const char *format_name(GLenum f)
{
    switch (f) {
    case GL_RGBA32F:
        return "rgba32f";
    case GL_RG32F:
        return "rg32f";
    case GL_RG16_SNORM:
        return "rg16_snorm";
    case GL_R32F:
        return "r32f";
    case GL_SRGB8_ALPHA8:
        return "srgb8_alpha8";
    default:
        return "rgba8";
    }
}

/* Each sample's position in its pixel and their mean, which lighting
 * rebuilds positions at (gbuffer.glsl). */
static void query_sample_positions(struct gbuffer *g, GLuint fbo)
{
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    g->sample_centre[0] = g->sample_centre[1] = 0.0f;
    for (int i = 0; i < g->samples; i++) {
        glGetMultisamplefv(GL_SAMPLE_POSITION, (GLuint)i, &g->sample_pos[2 * i]);
        g->sample_centre[0] += g->sample_pos[2 * i] / (float)g->samples;
        g->sample_centre[1] += g->sample_pos[2 * i + 1] / (float)g->samples;
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

static bool edges_init(struct gbuffer *g, const struct technique_env *env, char *err,
                       size_t errlen)
{
    query_sample_positions(g, g->fbo);
    /* A stencil of its own rather than the output's: lighting samples the
     * output's depth, which must not be attached while it does. */
    g->edge_tex = gpu_targets_texture_ms(env->targets, "gbuffer.edges", GL_DEPTH24_STENCIL8,
                                         env->width, env->height, g->samples, err, errlen);
    GLuint none = 0;
    g->edge_fbo = g->edge_tex ? gpu_targets_fbo(env->targets, "gbuffer.edges", &none, 0,
                                                g->edge_tex, err, errlen)
                              : 0;
    if (!g->edge_fbo)
        return false;
    const struct gl_stage edge[] = {
        {GL_VERTEX_SHADER, {"fullscreen.vert"}},
        {GL_FRAGMENT_SHADER, {"gbuffer_edges.frag"}},
    };
    const struct gl_stage fold[] = {{GL_COMPUTE_SHADER, {"gbuffer_edges_fold.comp"}}};
    if (!(g->edge_prog = gbuffer_program(g, "g-buffer edges", edge, 2, "", false, err, errlen)) ||
        !(g->fold_prog = gl_program_build("g-buffer edge count", fold, 1, NULL, err, errlen)))
        return false;
    glGenBuffers(1, &g->stats_buf);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->stats_buf);
    glBufferData(GL_SHADER_STORAGE_BUFFER, 8 * sizeof(GLuint), NULL, GL_DYNAMIC_READ);
    glClearBufferData(GL_SHADER_STORAGE_BUFFER, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, NULL);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    glGenVertexArrays(1, &g->empty_vao);
    return true;
}

GLuint gbuffer_program(const struct gbuffer *g, const char *label, const struct gl_stage *stages,
                       int nstages, const char *extra, bool per_sample, char *err, size_t errlen)
{
    size_t n = strlen(extra) + strlen(g->defines) + 64;
    char *defines = malloc(n);
    if (!defines) {
        snprintf(err, errlen, "%s: out of memory", label);
        return 0;
    }
    snprintf(defines, n, "%s%s%s", extra, per_sample ? "#define GBUFFER_PER_SAMPLE 1\n" : "",
             g->defines);
    GLuint prog = gl_program_build(label, stages, nstages, defines, err, errlen);
    free(defines);
    if (prog && g->samples > 1) {
        GLint pos = glGetUniformLocation(prog, "u_sample_pos");
        GLint centre = glGetUniformLocation(prog, "u_sample_centre");
        if (pos >= 0)
            glProgramUniform2fv(prog, pos, g->samples, g->sample_pos);
        if (centre >= 0)
            glProgramUniform2fv(prog, centre, 1, g->sample_centre);
    }
    return prog;
}

bool gbuffer_init(struct gbuffer *g, const struct technique_env *env,
                  const struct gbuffer_options *opt, char *err, size_t errlen)
{
    memset(g, 0, sizeof(*g));
    g->opt = *opt;
    snprintf(g->defines, sizeof(g->defines), "%s%s%s", normal_defines[opt->normal],
             albedo_defines[opt->albedo], env->defines ? env->defines : "");
    g->albedo_format = opt->albedo == GBUFFER_ALBEDO_RGBA8 ? GL_RGBA8 : GL_R32F;
    /* Asset scenes: 8 bits a channel sRGB-encoded, as the textures the
     * albedo comes from are. Linear 8 bits put steps of 1/255 into dark
     * base colours that the sRGB texels resolve finely, and a textured
     * scene lit by many lights shows them (PerceptualDiff failed
     * clustered_deferred against forward on the showcase asset with 256
     * lights). The procedural scenes keep their linear plane. */
    if (g->albedo_format == GL_RGBA8 && env->scene->asset)
        g->albedo_format = GL_SRGB8_ALPHA8;
    switch (opt->normal) {
    case GBUFFER_NORMAL_FLOAT3:
        g->normal_format = GL_RGBA32F;
        break;
    case GBUFFER_NORMAL_XY_RECONSTRUCT_Z:
        g->normal_format = GL_RG32F;
        break;
    default:
        /* 16-bit signed normalised where the device renders to it (3e-5 of
         * error, far below what an 8-bit image shows), else floats. */
        g->normal_format = renderable(GL_RG16_SNORM) ? GL_RG16_SNORM : GL_RG32F;
        break;
    }
    g->samples = env->samples > 1 ? env->samples : 1;
    g->pixels = env->width * env->height;
    g->albedo_tex = gpu_targets_texture_ms(env->targets, "gbuffer.albedo", g->albedo_format,
                                           env->width, env->height, g->samples, err, errlen);
    g->normal_tex = g->albedo_tex ? gpu_targets_texture_ms(env->targets, "gbuffer.normal",
                                                           g->normal_format, env->width,
                                                           env->height, g->samples, err, errlen)
                                  : 0;
    /* Metallic and roughness ride along only where the look reads them. */
    g->material_format = env->look->lighting == LOOK_PBR ? GL_RGBA32F : GL_RG32F;
    g->material_tex = g->normal_tex ? gpu_targets_texture_ms(env->targets, "gbuffer.material",
                                                             g->material_format, env->width,
                                                             env->height, g->samples, err,
                                                             errlen)
                                    : 0;
    bool textured = env->scene->asset != NULL;
    if (g->material_tex && textured)
        g->surface_tex = gpu_targets_texture_ms(env->targets, "gbuffer.surface", GL_RGBA16F,
                                                env->width, env->height, g->samples, err, errlen);
    GLuint planes[4] = {g->albedo_tex, g->normal_tex, g->material_tex, g->surface_tex};
    g->fbo = g->material_tex && (!textured || g->surface_tex)
                 ? gpu_targets_fbo(env->targets, textured ? "gbuffer.textured" : "gbuffer", planes,
                                   textured ? 4 : 3, env->output_depth, err, errlen)
                 : 0;
    if (!g->fbo)
        return false;
    const struct gl_stage stages[] = {
        {GL_VERTEX_SHADER, {"scene.vert"}},
        {GL_FRAGMENT_SHADER, {"gbuffer.frag"}},
    };
    GLuint prog = gl_program_build("g-buffer", stages, 2, g->defines, err, errlen);
    if (!prog)
        return false;
    g->program = gpu_scene_program(env->gpu, prog);
    if (g->samples > 1 && !edges_init(g, env, err, errlen))
        return false;
    /* Post effects read single-sample normals: at msaa > 1 they rebuild them
     * from the resolved depth, as for the sign-losing layout. */
    if (opt->normal != GBUFFER_NORMAL_XY_RECONSTRUCT_Z && g->samples == 1) {
        /* The sign-losing layout is no normal a post effect could use: it
         * rebuilds normals from depth instead. */
        env->products->normal_tex = g->normal_tex;
        env->products->normal_encoding = opt->normal == GBUFFER_NORMAL_FLOAT3
                                             ? TECHNIQUE_NORMAL_FLOAT3
                                             : TECHNIQUE_NORMAL_OCTAHEDRAL;
    }
    return true;
}

void gbuffer_finish(struct gbuffer *g)
{
    if (g->program.prog)
        glDeleteProgram(g->program.prog);
    g->program.prog = 0;
    glDeleteProgram(g->edge_prog);
    glDeleteProgram(g->fold_prog);
    glDeleteBuffers(1, &g->stats_buf);
    glDeleteVertexArrays(1, &g->empty_vao);
    g->edge_prog = g->fold_prog = g->stats_buf = g->empty_vao = 0;
}

void gbuffer_edges_draw(const struct gbuffer *g, const struct technique_env *env, int pass,
                        int64_t frame)
{
    gpu_pass_begin(env->passes, pass, g->samples > 1 ? g->edge_fbo : env->output_fbo,
                   env->width, env->height);
    if (g->samples > 1) {
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SB_SSBO_EDGE_STATS, g->stats_buf);
        if (frame == 1)
            glClearBufferData(GL_SHADER_STORAGE_BUFFER, GL_R32UI, GL_RED_INTEGER,
                              GL_UNSIGNED_INT, NULL);
        glClearStencil(0);
        glClear(GL_STENCIL_BUFFER_BIT);
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        /* The fragments the edge test keeps cover every sample of their
         * pixel: the whole pixel is marked. */
        glEnable(GL_STENCIL_TEST);
        glStencilFunc(GL_ALWAYS, 1, 0xff);
        glStencilOp(GL_KEEP, GL_KEEP, GL_REPLACE);
        glStencilMask(0xff);
        gbuffer_bind(g, env);
        glUseProgram(g->edge_prog);
        glBindVertexArray(g->empty_vao);
        struct gpu_tiles t;
        for (gpu_tiles_begin(env->budget, env->width, env->height, &t);
             gpu_tiles_next(env->budget, &t);)
            glDrawArrays(GL_TRIANGLES, 0, 3);
        glBindVertexArray(0);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        glUseProgram(g->fold_prog);
        glDispatchCompute(1, 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        glDisable(GL_STENCIL_TEST);
    }
    gpu_pass_end(env->passes);
}

GLuint gbuffer_light_fbo(const struct gbuffer *g, const struct technique_env *env,
                         const char *name, char *err, size_t errlen)
{
    return gpu_targets_fbo(env->targets, name, &env->output_color, 1,
                           g->samples > 1 ? g->edge_tex : 0, err, errlen);
}

void gbuffer_shading_state(const struct gbuffer *g, int run)
{
    if (g->samples <= 1)
        return;
    glEnable(GL_STENCIL_TEST);
    glStencilFunc(GL_EQUAL, run, 0xff);
    glStencilOp(GL_KEEP, GL_KEEP, GL_KEEP);
    glStencilMask(0);
}

void gbuffer_draw(const struct gbuffer *g, const struct technique_env *env, int pass)
{
    static const GLfloat zero[4] = {0, 0, 0, 0};
    gpu_pass_begin(env->passes, pass, g->fbo, env->width, env->height);
    glClearBufferfv(GL_COLOR, 0, zero);
    glClearBufferfv(GL_COLOR, 1, zero);
    glClearBufferfv(GL_COLOR, 2, zero);
    if (g->surface_tex)
        glClearBufferfv(GL_COLOR, 3, zero);
    glClear(GL_DEPTH_BUFFER_BIT);
    gpu_scene_bind(env->gpu, &g->program);
    /* An sRGB albedo plane is encoded on write only with this on (the
     * other planes are linear formats, which it leaves alone). */
    if (g->albedo_format == GL_SRGB8_ALPHA8)
        glEnable(GL_FRAMEBUFFER_SRGB);
    gpu_scene_draw(env->gpu, &g->program);
    glDisable(GL_FRAMEBUFFER_SRGB);
    gpu_pass_end(env->passes);
}

void gbuffer_bind(const struct gbuffer *g, const struct technique_env *env)
{
    GLenum kind = g->samples > 1 ? GL_TEXTURE_2D_MULTISAMPLE : GL_TEXTURE_2D;
    glActiveTexture(GL_TEXTURE0 + SB_TEX_DEPTH);
    glBindTexture(kind, env->output_depth);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_GBUFFER0);
    glBindTexture(kind, g->albedo_tex);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_GBUFFER1);
    glBindTexture(kind, g->normal_tex);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_GBUFFER2);
    glBindTexture(kind, g->material_tex);
    if (g->surface_tex) {
        glActiveTexture(GL_TEXTURE0 + SB_TEX_GBUFFER3);
        glBindTexture(kind, g->surface_tex);
    }
    glActiveTexture(GL_TEXTURE0);
}

/* The edge pixels over the timed frames, read back once after the run. */
static json_t *msaa_describe(const struct gbuffer *g, int pixels)
{
    if (g->samples <= 1)
        return json_pack("{s:i, s:s}", "samples", 1, "shading", "once a pixel");
    GLuint v[8] = {0};
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->stats_buf);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof(v), v);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    double frames = v[1], sum = (double)v[5] * 4294967296.0 + v[4];
    double mean = frames > 0 ? sum / frames : 0;
    return json_pack("{s:i, s:{s:i, s:f, s:i, s:i, s:f, s:i}, s:s, s:s}", "samples", g->samples,
                     "edge_pixels", "frames", (int)v[1], "mean", mean, "max", (int)v[2],
                     "last_frame", (int)v[3], "fraction_mean", pixels > 0 ? mean / pixels : 0.0,
                     "pixels", pixels, "edges",
                     "pixels whose samples differ in coverage (background or not), normal, "
                     "albedo or material, or lie off sample 0's plane: marked by the edges "
                     "pass in a stencil, shaded once a sample (the rest once a pixel, at the "
                     "centre of the sample pattern)",
                     "shading", "per pixel where unmarked, per sample where marked");
}

json_t *gbuffer_describe(const struct gbuffer *g)
{
    json_t *d = json_pack("{s:s, s:s, s:s, s:s, s:s, s:f, s:s}", "normal",
                     gbuffer_normal_choices[g->opt.normal], "normal_format",
                     format_name(g->normal_format), "albedo",
                     gbuffer_albedo_choices[g->opt.albedo], "albedo_format",
                     format_name(g->albedo_format), "material_format",
                     g->material_format == GL_RGBA32F
                         ? "rgba32f (specular, shininess, metallic, roughness)"
                         : "rg32f (specular, shininess)",
                     "bytes_per_pixel",
                     (format_bytes(g->albedo_format) + format_bytes(g->normal_format) +
                      format_bytes(g->material_format) + (g->surface_tex ? 8.0 : 0.0) + 4.0 +
                      (g->samples > 1 ? 4.0 : 0.0)) *
                         g->samples,
                     "position", "rebuilt from the 24-bit depth texture with inv_view_proj");
    json_object_set_new(d, "msaa", msaa_describe(g, g->pixels));
    if (g->surface_tex)
        json_object_set_new(d, "surface_format",
                            json_string("rgba16f (emissive, occlusion): asset materials"));
    return d;
}
