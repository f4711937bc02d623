#include "daemon/look/debug.h"

#include <string.h>

#include "daemon/gpu/glutil.h"

bool look_debug_init(struct look_debug_pass *d, const struct gpu_scene *gpu, const char *defines,
                     char *err, size_t errlen)
{
    memset(d, 0, sizeof(*d));
    const struct gl_stage stages[] = {
        {GL_VERTEX_SHADER, {"scene.vert"}},
        {GL_FRAGMENT_SHADER, {"debug.frag"}},
    };
    GLuint prog = gl_program_build("debug", stages, 2, defines, err, errlen);
    if (!prog)
        return false;
    d->program = gpu_scene_program(gpu, prog);
    return true;
}

void look_debug_draw(const struct look_debug_pass *d, const struct gpu_scene *gpu)
{
    glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    glClearDepth(1.0);
    glDepthMask(GL_TRUE);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glDisable(GL_BLEND);
    gpu_scene_bind(gpu, &d->program);
    gpu_scene_draw(gpu, &d->program);
}

void look_debug_finish(struct look_debug_pass *d)
{
    if (!d)
        return;
    if (d->program.prog)
        glDeleteProgram(d->program.prog);
    memset(d, 0, sizeof(*d));
}
