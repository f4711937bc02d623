#ifndef SHADEBENCH_GBUFFER_H
#define SHADEBENCH_GBUFFER_H

/* The g-buffer every deferred technique draws: an albedo plane and a
 * normal plane in the layouts the job's gbuffer options choose
 * (shaders/deferred/gbuffer.glsl) and a material plane (specular weight and exponent, exact), over the
 * output's depth texture, from which lighting rebuilds positions with the
 * frame block's inverse view-projection. Lossless layouts publish their
 * normals in env->products for post effects. Render thread only. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "daemon/techniques/shared/culling_info.h"
#include "daemon/techniques/technique.h"

struct gbuffer {
    struct gbuffer_options opt;
    GLuint albedo_tex, normal_tex, material_tex, fbo;
    GLenum albedo_format, normal_format, material_format;
    struct scene_program program;
    /* The layout's #defines and the look's, for every program that reads the
     * g-buffer (pass to gl_program_build). */
    char defines[768];
};

/* Allocates the planes from the pool and builds the g-buffer program. On
 * failure g holds nothing to free. */
bool gbuffer_init(struct gbuffer *g, const struct technique_env *env,
                  const struct gbuffer_options *opt, char *err, size_t errlen);
/* Frees what init made (the planes belong to the pool). Accepts a zeroed g. */
void gbuffer_finish(struct gbuffer *g);

/* Pass `pass`: clears and draws every object into the planes and the
 * output's depth texture. */
void gbuffer_draw(const struct gbuffer *g, const struct technique_env *env, int pass);

/* Binds depth and planes on their texture units for lighting. */
void gbuffer_bind(const struct gbuffer *g, const struct technique_env *env);

/* Layout and bytes per pixel, for describe(). New reference. */
json_t *gbuffer_describe(const struct gbuffer *g);

#endif
