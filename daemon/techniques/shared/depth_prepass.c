#include "daemon/techniques/shared/depth_prepass.h"

#include "daemon/gpu/glutil.h"

bool depth_prepass_init(struct depth_prepass *d, const struct technique_env *env, char *err,
                        size_t errlen)
{
    const struct gl_stage stages[] = {
        {GL_VERTEX_SHADER, {"scene.vert"}},
        {GL_FRAGMENT_SHADER, {"depth_only.frag"}},
    };
    GLuint prog = gl_program_build("depth pre-pass", stages, 2, env->defines, err, errlen);
    if (!prog)
        return false;
    d->program = gpu_scene_program(env->gpu, prog);
    return true;
}

void depth_prepass_finish(struct depth_prepass *d)
{
    if (d->program.prog)
        glDeleteProgram(d->program.prog);
    d->program.prog = 0;
}

void depth_prepass_draw(const struct depth_prepass *d, const struct technique_env *env, int pass)
{
    gpu_pass_begin(env->passes, pass, env->output_fbo, env->width, env->height);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClearStencil(0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    gpu_scene_bind(env->gpu, &d->program);
    gpu_scene_draw(env->gpu, &d->program);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gpu_pass_end(env->passes);
}

void depth_prepass_shading_state(void)
{
    glDepthFunc(GL_LEQUAL);
    glDepthMask(GL_FALSE);
    /* Where two surfaces have the same depth (a cube standing on the
     * ground), GL_LEQUAL passes both and the last one drawn would win, while
     * forward's GL_LESS keeps the first. The first fragment to pass marks the
     * pixel, so later ones at the same depth fail, as in forward. */
    glEnable(GL_STENCIL_TEST);
    glStencilFunc(GL_EQUAL, 0, 0xff);
    glStencilOp(GL_KEEP, GL_KEEP, GL_INCR);
    glStencilMask(0xff);
}
