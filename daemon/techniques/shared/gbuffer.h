#ifndef SHADEBENCH_GBUFFER_H
#define SHADEBENCH_GBUFFER_H

/* The g-buffer every deferred technique draws: an albedo plane and a
 * normal plane in the layouts the job's gbuffer options choose
 * (shaders/deferred/gbuffer.glsl) and a material plane (specular weight and exponent, exact), over the
 * output's depth texture, from which lighting rebuilds positions with the
 * frame block's inverse view-projection. Lossless layouts publish their
 * normals in env->products for post effects.
 *
 * With MSAA (env->samples > 1) the planes are multisampled like the output,
 * and the edge pass (gbuffer_edges_draw) marks, in the stencil of a target
 * of its own, the pixels whose samples hold more than one surface: lighting
 * runs twice (gbuffer_shading_state), once a pixel where unmarked and once a
 * sample where marked, as real renderers do. The edge pixels are counted on
 * the GPU and reported by gbuffer_describe. Render thread only. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "daemon/gpu/glutil.h"
#include "daemon/techniques/shared/culling_info.h"
#include "daemon/techniques/technique.h"

struct gbuffer {
    struct gbuffer_options opt;
    GLuint albedo_tex, normal_tex, material_tex, fbo;
    GLenum albedo_format, normal_format, material_format;
    /* Asset scenes: a fourth plane, emissive and occlusion (rgba16f), what
     * the textures give beyond the material plane; 0 for the presets. */
    GLuint surface_tex;
    struct scene_program program;
    /* The layout's #defines and the look's, for every program that reads the
     * g-buffer (pass to gl_program_build). */
    char defines[768];
    /* MSAA: samples a pixel; the edge target (GL_DEPTH24_STENCIL8, its
     * stencil 1 on edge pixels) and its framebuffer, the edge and fold
     * programs, the counters (SB_SSBO_EDGE_STATS), sample positions. */
    int samples, pixels;
    GLuint edge_tex, edge_fbo, edge_prog, fold_prog, stats_buf, empty_vao;
    float sample_pos[2 * 8], sample_centre[2];
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

/* Pass `pass`, the edge pass: at msaa 1 an empty pass (no edges to find,
 * timed at about 0), else the stencil marks and the count (reset at timed
 * frame 1, so that the figures cover the timed frames). */
void gbuffer_edges_draw(const struct gbuffer *g, const struct technique_env *env, int pass,
                        int64_t frame);

/* A framebuffer over the output's colour for lighting, with the edge
 * stencil at msaa > 1. */
GLuint gbuffer_light_fbo(const struct gbuffer *g, const struct technique_env *env,
                         const char *name, char *err, size_t errlen);

/* A program that reads the g-buffer, built with extra #defines, g's and,
 * when per_sample, GBUFFER_PER_SAMPLE (it then runs once a sample); the
 * sample positions are set on it. 0 with err. */
GLuint gbuffer_program(const struct gbuffer *g, const char *label, const struct gl_stage *stages,
                       int nstages, const char *extra, bool per_sample, char *err,
                       size_t errlen);

/* Lighting runs gbuffer_shading_runs(g) times (1, or 2 at msaa > 1); run
 * `run` sets the stencil test that keeps its pixels: 0 unmarked (per pixel),
 * 1 marked (per sample, with the per_sample program). */
static inline int gbuffer_shading_runs(const struct gbuffer *g) { return g->samples > 1 ? 2 : 1; }
void gbuffer_shading_state(const struct gbuffer *g, int run);

/* Binds depth and planes on their texture units for lighting. */
void gbuffer_bind(const struct gbuffer *g, const struct technique_env *env);

/* Layout and bytes per pixel, for describe(). New reference. */
json_t *gbuffer_describe(const struct gbuffer *g);

#endif
