#ifndef SHADEBENCH_GPU_SCENE_H
#define SHADEBENCH_GPU_SCENE_H

/* The scene's GL objects, shared by every technique: one VAO per mesh, the
 * instance buffer (position and scale, albedo and mesh, material), the
 * light buffers and per-frame light positions; for asset scenes the
 * material buffer (SB_SSBO_MATERIALS), the images as textures with mipmaps
 * (GL_SRGB8_ALPHA8 where a material samples them as base colour or
 * emissive, GL_RGBA8 for the other slots: an image in both roles gets two)
 * and a sampler per material slot, bound per asset mesh by gpu_scene_draw.
 * Render thread only (it holds the GL context). */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/scene/scene.h"

struct gpu_scene {
    const struct scene *scene;
    GLuint *vao, *vbo, *ebo; /* per mesh of the scene (scene.mesh_count) */
    int mesh_count;
    GLuint instance_buffer, light_buffer, position_buffer;
    int position_rows;          /* rows allocated in position_buffer */
    int64_t uploaded_frame;     /* frame in row 0 when rows == 1, else INT64_MIN */
    float *position_scratch;
    /* Asset scenes: the material buffer, the textures (image_tex[2 i]
     * linear and [2 i + 1] sRGB, 0 where unused), and per scene mesh the
     * material index and its five units' textures and samplers, looked up
     * once at init so a draw only binds. */
    GLuint material_buffer;
    GLuint *image_tex;
    int image_tex_count;
    GLuint *samplers; /* per asset material and slot */
    int sampler_count;
    struct gpu_mesh_material {
        int material; /* index into the buffer (the default material last) */
        bool double_sided;
        int attributes; /* the file's: bit 0 TEXCOORD_0, 1 TEXCOORD_1, 2 COLOR_0 */
        GLuint tex[5], sampler[5];
    } *mesh_material; /* per scene mesh; NULL without an asset */
    /* Scenes with a mover (scene.mover): the instance rows kept here, so
     * that each frame's upload orphans the buffer rather than waiting for a
     * frame in flight; every instance's position and scale the frame
     * before (SB_SSBO_PREV_INSTANCES, for motion vectors; the current ones
     * in scenes without a mover); the frame uploaded (INT64_MIN: none). */
    float *instance_rows;
    GLuint prev_instance_buffer;
    int64_t instances_frame;
};

/* Which meshes gpu_scene_draw draws: the techniques' passes draw opaque and
 * alpha-masked ones; the harness's transparent pass the blended ones. */
enum gpu_draw_set { GPU_DRAW_OPAQUE_MASKED, GPU_DRAW_BLENDED };

bool gpu_scene_init(struct gpu_scene *g, const struct scene *s, char *err, size_t errlen);
void gpu_scene_finish(struct gpu_scene *g);

/* Uploads light positions, row r holding frames[r]; rows == 1 for techniques
 * that light the current frame only. Skips the upload when unchanged. The
 * camera is not the scene's business here: the harness puts each frame's in
 * the frame block (daemon/gpu/pass.h). */
void gpu_scene_set_light_rows(struct gpu_scene *g, const int64_t *frames, int rows);

/* Puts the instances where they are at frame (the harness calls it before
 * each frame's passes) and the frame before's positions in the previous
 * rows; nothing in a scene where nothing moves. */
void gpu_scene_set_frame(struct gpu_scene *g, int64_t frame);

/* A program that reads the scene, with the uniforms the scene sets. */
struct scene_program {
    GLuint prog;
    GLint instance_base; /* -1 for programs that draw no instances */
    GLint material;      /* SB_LOC_MATERIAL, or -1 where the program reads no material */
    /* Shading after a depth pre-pass (GL_LEQUAL, depth writes off, the
     * stencil keeping the first fragment): alpha-masked meshes draw with
     * GL_EQUAL instead, so that a fragment the mask discards, nearer than
     * the depth the pre-pass kept, never passes the early tests (which
     * would mark the stencil before the discard). Set by the technique. */
    bool after_prepass;
    /* SB_LOC_MESH_ATTRIBUTES where the program reads it (look.debug's),
     * else -1. */
    GLint mesh_attributes;
};

/* Looks up prog's per-draw uniform once, so that frames only bind: no
 * uniform lookups in the timed region. */
struct scene_program gpu_scene_program(const struct gpu_scene *g, GLuint prog);

/* Uses the program and binds the scene buffers at their bindings.h points. */
void gpu_scene_bind(const struct gpu_scene *g, const struct scene_program *p);

/* Instanced draw of every opaque and alpha-masked object, one call per mesh
 * (all of a procedural scene); asset meshes with their material bound
 * first (textures on SB_TEX_MATERIAL_*, SB_LOC_MATERIAL, face culling off
 * for double-sided ones). */
void gpu_scene_draw(const struct gpu_scene *g, const struct scene_program *p);
/* One mesh of the scene (its instances), material bound: the transparent
 * pass's draw, in its own order. */
void gpu_scene_draw_mesh(const struct gpu_scene *g, const struct scene_program *p, int mesh);
/* One instance (its mesh's draw of one), material bound: the harness's
 * motion vectors of a moving instance. */
void gpu_scene_draw_instance(const struct gpu_scene *g, const struct scene_program *p,
                             int instance);
/* Binds mesh's material (asset meshes; nothing for procedural ones): for
 * passes that draw meshes their own way (the shadow casters). */
void gpu_scene_bind_material(const struct gpu_scene *g, int mesh, GLint material_loc);

/* Texture units the material path needs: false with err when the device has
 * too few (GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS, GL_MAX_TEXTURE_IMAGE_UNITS). */
bool gpu_scene_check_units(char *err, size_t errlen);

#endif
