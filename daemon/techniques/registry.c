/* The registry: one line per technique. Everything else about a technique
 * lives in its own file or folder. */
#include "daemon/techniques/technique.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/gpu/glutil.h"

extern const struct technique technique_forward, technique_unlit, technique_osl;
extern const struct technique technique_deferred, technique_tiled_deferred,
    technique_forward_plus, technique_clustered_forward, technique_clustered_deferred;

const struct technique *const technique_registry[] = {
    &technique_forward,
    &technique_unlit,
    &technique_osl,
    &technique_deferred,
    &technique_tiled_deferred,
    &technique_forward_plus,
    &technique_clustered_forward,
    &technique_clustered_deferred,
    NULL,
};

const struct technique *technique_find(const char *name)
{
    for (const struct technique *const *t = technique_registry; *t; t++)
        if (strcmp((*t)->info->name, name) == 0)
            return *t;
    return NULL;
}

int technique_pass_count(const struct technique *t)
{
    int n = 0;
    while (t->info->passes && t->info->passes[n])
        n++;
    return n;
}

bool technique_check(const struct technique *t, char *err, size_t errlen)
{
    const struct technique_info *i = t->info;
    if (!i || !i->name || !i->summary || !t->create || !t->render || !t->destroy) {
        snprintf(err, errlen, "technique %s: info, name, summary, create, render and destroy "
                 "are mandatory", i && i->name ? i->name : "(unnamed)");
        return false;
    }
    int passes = technique_pass_count(t);
    if (passes < 1 || passes > TECHNIQUE_MAX_PASSES) {
        snprintf(err, errlen, "technique %s: declares %d passes; 1 to %d allowed", i->name, passes,
                 TECHNIQUE_MAX_PASSES);
        return false;
    }
    if (i->options_size > TECHNIQUE_OPTIONS_BYTES) {
        snprintf(err, errlen, "technique %s: options take %zu bytes; %d fit in a job", i->name,
                 i->options_size, TECHNIQUE_OPTIONS_BYTES);
        return false;
    }
    return true;
}

static struct technique_catalog catalog;
static char catalog_error[256];

const struct technique_catalog *technique_catalog(void)
{
    if (catalog.count || catalog_error[0])
        return catalog_error[0] ? NULL : &catalog;
    for (const struct technique *const *t = technique_registry; *t; t++)
        if (!technique_check(*t, catalog_error, sizeof(catalog_error)) ||
            !technique_catalog_add(&catalog, (*t)->info)) {
            if (!catalog_error[0])
                snprintf(catalog_error, sizeof(catalog_error),
                         "technique %s: duplicate name or the catalogue is full", (*t)->info->name);
            return NULL;
        }
    return &catalog;
}

const char *technique_catalog_error(void) { return catalog_error; }

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
    (void)err, (void)errlen;
    struct single_pass *sp = state;
    gpu_scene_set_light_rows(env->gpu, &frame, 1);
    gpu_pass_begin(env->passes, 0, env->output_fbo, env->width, env->height);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    gpu_scene_bind(env->gpu, &sp->program);
    gpu_scene_draw(env->gpu, &sp->program);
    gpu_pass_end(env->passes);
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
