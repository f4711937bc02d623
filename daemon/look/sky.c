#include "daemon/look/sky.h"

#include <string.h>

#include "daemon/gpu/bindings.h"
#include "daemon/gpu/glutil.h"

bool look_sky_init(struct look_sky *s, const char *defines, const struct environment_image *env,
                   char *err, size_t errlen)
{
    memset(s, 0, sizeof(*s));
    if (env) {
        /* Repeat across the seam in u (azimuth), clamp at the poles; the
         * shader picks the level from a pixel's solid angle. */
        int levels = 1;
        for (uint32_t m = env->width > env->height ? env->width : env->height; m > 1; m >>= 1)
            levels++;
        glGenTextures(1, &s->env_map);
        glBindTexture(GL_TEXTURE_2D, s->env_map);
        glTexStorage2D(GL_TEXTURE_2D, levels, GL_RGB32F, (GLsizei)env->width,
                       (GLsizei)env->height);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, (GLsizei)env->width, (GLsizei)env->height,
                        GL_RGB, GL_FLOAT, env->rgb);
        glGenerateMipmap(GL_TEXTURE_2D);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        glBindTexture(GL_TEXTURE_2D, 0);
        s->env_bytes = (double)env->width * env->height * 12.0 * 4.0 / 3.0;
    }
    const struct gl_stage stages[] = {
        {GL_VERTEX_SHADER, {"sky.vert"}},
        {GL_FRAGMENT_SHADER, {"sky.frag"}},
    };
    s->prog = gl_program_build("sky", stages, 2, defines, err, errlen);
    if (!s->prog)
        return false;
    glGenVertexArrays(1, &s->vao);
    return true;
}

void look_sky_draw(const struct look_sky *s)
{
    glDepthFunc(GL_LEQUAL);
    glDepthMask(GL_FALSE);
    glDisable(GL_CULL_FACE);
    glUseProgram(s->prog);
    if (s->env_map) {
        glActiveTexture(GL_TEXTURE0 + SB_TEX_ENV_MAP);
        glBindTexture(GL_TEXTURE_2D, s->env_map);
        glActiveTexture(GL_TEXTURE0);
    }
    glBindVertexArray(s->vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LESS);
}

void look_sky_finish(struct look_sky *s)
{
    if (!s)
        return;
    if (s->prog)
        glDeleteProgram(s->prog);
    if (s->vao)
        glDeleteVertexArrays(1, &s->vao);
    if (s->env_map)
        glDeleteTextures(1, &s->env_map);
    memset(s, 0, sizeof(*s));
}
