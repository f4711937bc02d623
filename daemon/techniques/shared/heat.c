#include "daemon/techniques/shared/heat.h"

#include "daemon/gpu/bindings.h"

bool heat_init(struct heat *h, const struct technique_env *env, char *err, size_t errlen)
{
    h->tex = gpu_targets_texture(env->targets, "heat", GL_R32UI, env->width, env->height, err,
                                 errlen);
    h->fbo = h->tex ? gpu_targets_fbo(env->targets, "heat", &h->tex, 1, 0, err, errlen) : 0;
    if (!h->fbo)
        return false;
    env->products->heat_tex = h->tex;
    return true;
}

bool heat_wanted(const struct technique_env *env, int64_t frame)
{
    return technique_env_captures(env, frame);
}

GLint heat_location(GLuint prog) { return glGetUniformLocation(prog, "u_heat_on"); }

void heat_enable(GLuint prog, GLint location, bool on)
{
    glProgramUniform1i(prog, location, on ? 1 : 0);
}

void heat_clear(const struct heat *h, GLuint restore_fbo)
{
    static const GLuint zero[4] = {0, 0, 0, 0};
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, h->fbo);
    glClearBufferuiv(GL_COLOR, 0, zero);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, restore_fbo);
    heat_bind(h);
}

void heat_bind(const struct heat *h)
{
    glBindImageTexture(SB_IMG_HEAT, h->tex, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32UI);
}

void heat_done(void)
{
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
}
