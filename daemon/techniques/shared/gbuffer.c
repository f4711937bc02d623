#include "daemon/techniques/shared/gbuffer.h"

#include <stdio.h>
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
    default:
        return "rgba8";
    }
}

bool gbuffer_init(struct gbuffer *g, const struct technique_env *env,
                  const struct gbuffer_options *opt, char *err, size_t errlen)
{
    memset(g, 0, sizeof(*g));
    g->opt = *opt;
    snprintf(g->defines, sizeof(g->defines), "%s%s%s", normal_defines[opt->normal],
             albedo_defines[opt->albedo], env->defines ? env->defines : "");
    g->albedo_format = opt->albedo == GBUFFER_ALBEDO_RGBA8 ? GL_RGBA8 : GL_R32F;
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
    g->albedo_tex = gpu_targets_texture(env->targets, "gbuffer.albedo", g->albedo_format,
                                        env->width, env->height, err, errlen);
    g->normal_tex = g->albedo_tex ? gpu_targets_texture(env->targets, "gbuffer.normal",
                                                        g->normal_format, env->width,
                                                        env->height, err, errlen)
                                  : 0;
    g->material_tex = g->normal_tex ? gpu_targets_texture(env->targets, "gbuffer.material",
                                                          GL_RG32F, env->width, env->height,
                                                          err, errlen)
                                    : 0;
    GLuint planes[3] = {g->albedo_tex, g->normal_tex, g->material_tex};
    g->fbo = g->material_tex ? gpu_targets_fbo(env->targets, "gbuffer", planes, 3,
                                               env->output_depth, err, errlen)
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
    if (opt->normal != GBUFFER_NORMAL_XY_RECONSTRUCT_Z) {
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
}

void gbuffer_draw(const struct gbuffer *g, const struct technique_env *env, int pass)
{
    static const GLfloat zero[4] = {0, 0, 0, 0};
    gpu_pass_begin(env->passes, pass, g->fbo, env->width, env->height);
    glClearBufferfv(GL_COLOR, 0, zero);
    glClearBufferfv(GL_COLOR, 1, zero);
    glClearBufferfv(GL_COLOR, 2, zero);
    glClear(GL_DEPTH_BUFFER_BIT);
    gpu_scene_bind(env->gpu, &g->program);
    gpu_scene_draw(env->gpu, &g->program);
    gpu_pass_end(env->passes);
}

void gbuffer_bind(const struct gbuffer *g, const struct technique_env *env)
{
    glActiveTexture(GL_TEXTURE0 + SB_TEX_DEPTH);
    glBindTexture(GL_TEXTURE_2D, env->output_depth);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_GBUFFER0);
    glBindTexture(GL_TEXTURE_2D, g->albedo_tex);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_GBUFFER1);
    glBindTexture(GL_TEXTURE_2D, g->normal_tex);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_GBUFFER2);
    glBindTexture(GL_TEXTURE_2D, g->material_tex);
    glActiveTexture(GL_TEXTURE0);
}

json_t *gbuffer_describe(const struct gbuffer *g)
{
    return json_pack("{s:s, s:s, s:s, s:s, s:s, s:f, s:s}", "normal",
                     gbuffer_normal_choices[g->opt.normal], "normal_format",
                     format_name(g->normal_format), "albedo",
                     gbuffer_albedo_choices[g->opt.albedo], "albedo_format",
                     format_name(g->albedo_format), "material_format",
                     "rg32f (specular, shininess)", "bytes_per_pixel",
                     format_bytes(g->albedo_format) + format_bytes(g->normal_format) + 8.0 + 4.0,
                     "position", "rebuilt from the 24-bit depth texture with inv_view_proj");
}
