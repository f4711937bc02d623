#include "daemon/look/sky.h"

#include <string.h>

#include "daemon/gpu/glutil.h"

bool look_sky_init(struct look_sky *s, const char *defines, char *err, size_t errlen)
{
    memset(s, 0, sizeof(*s));
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
    memset(s, 0, sizeof(*s));
}
