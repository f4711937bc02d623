#include "daemon/techniques/technique.h"

#include <stdlib.h>
#include <string.h>

#include "daemon/gpu/glutil.h"

extern const struct technique technique_forward, technique_unlit, technique_osl;

const struct technique *const technique_registry[] = {
    &technique_forward,
    &technique_unlit,
    &technique_osl,
    NULL,
};

const struct technique *technique_find(const char *name)
{
    for (const struct technique *const *t = technique_registry; *t; t++)
        if (strcmp((*t)->name, name) == 0)
            return *t;
    return NULL;
}

const char *const *technique_names(void)
{
    static const char *names[16];
    if (!names[0])
        for (int i = 0; technique_registry[i] && i < 15; i++)
            names[i] = technique_registry[i]->name;
    return names;
}

int technique_section_count(const struct technique *t)
{
    int n = 0;
    while (t->sections[n])
        n++;
    return n;
}

struct single_pass {
    struct scene_program program;
};

bool single_pass_create(const struct technique_ctx *ctx, const char *label, const char *frag,
                        void **state, char *err, size_t errlen)
{
    struct single_pass *sp = calloc(1, sizeof(*sp));
    if (!sp)
        return false;
    const struct gl_stage stages[] = {
        {GL_VERTEX_SHADER, {"scene_data.glsl", "scene.vert"}},
        {GL_FRAGMENT_SHADER, {"scene_data.glsl", "lighting.glsl", frag}},
    };
    GLuint prog = gl_program_build(label, stages, 2, NULL, err, errlen);
    if (!prog) {
        free(sp);
        return false;
    }
    sp->program = gpu_scene_program(ctx->gpu, prog);
    *state = sp;
    return true;
}

bool single_pass_render(void *state, const struct technique_ctx *ctx,
                        int64_t frame, char *err, size_t errlen)
{
    (void)err, (void)errlen;
    struct single_pass *sp = state;
    gpu_scene_set_light_rows(ctx->gpu, &frame, 1);
    glEnable(GL_DEPTH_TEST);
    glEnable(GL_CULL_FACE);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    gpu_scene_bind(ctx->gpu, &sp->program);
    gpu_scene_draw(ctx->gpu, &sp->program);
    return true;
}

void single_pass_destroy(void *state)
{
    struct single_pass *sp = state;
    if (!sp)
        return;
    glDeleteProgram(sp->program.prog);
    free(sp);
}
