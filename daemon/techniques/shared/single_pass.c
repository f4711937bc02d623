#include "daemon/techniques/shared/single_pass.h"

#include <stdio.h>
#include <stdlib.h>

#include "daemon/gpu/glutil.h"

struct single_pass {
    struct scene_program program;
};

bool single_pass_create(const struct technique_env *env, const char *label, const char *frag,
                        void **state, char *err, size_t errlen)
{
    struct single_pass *sp = calloc(1, sizeof(*sp));
    if (!sp) {
        snprintf(err, errlen, "%s: out of memory", label);
        return false;
    }
    const struct gl_stage stages[] = {
        {GL_VERTEX_SHADER, {"scene.vert"}},
        {GL_FRAGMENT_SHADER, {frag}},
    };
    GLuint prog = gl_program_build(label, stages, 2, env->defines, err, errlen);
    if (!prog) {
        free(sp);
        return false;
    }
    sp->program = gpu_scene_program(env->gpu, prog);
    *state = sp;
    return true;
}

bool single_pass_render(void *state, const struct technique_env *env, int64_t frame, char *err,
                        size_t errlen)
{
    struct single_pass *sp = state;
    gpu_scene_set_light_rows(env->gpu, &frame, 1);
    gpu_pass_begin(env->passes, 0, env->output_fbo, env->width, env->height);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    gpu_scene_bind(env->gpu, &sp->program);
    struct gpu_tiles t;
    for (gpu_tiles_begin(env->budget, env->width, env->height, &t); gpu_tiles_next(env->budget, &t);)
        gpu_scene_draw(env->gpu, &sp->program);
    gpu_pass_end(env->passes);
    return technique_keep_going(env, err, errlen);
}

void single_pass_destroy(void *state)
{
    struct single_pass *sp = state;
    if (!sp)
        return;
    glDeleteProgram(sp->program.prog);
    free(sp);
}
