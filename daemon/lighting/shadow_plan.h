#ifndef SHADEBENCH_SHADOW_PLAN_H
#define SHADEBENCH_SHADOW_PLAN_H

/* Which lights get omni shadow maps this frame, at what size, and where
 * their faces lie in the atlas (GL-free: the harness's shadow pass renders
 * what the plan says, daemon/look/shadows.c).
 *
 * A light needs a map only when its sphere of influence reaches the view
 * frustum and holds a caster (an object other than the ground). A spot
 * light is a point light with a cone: the same six faces from its position
 * (far plane its radius), needed when its cone's bounding sphere reaches
 * the frustum and its cone a caster. A directional light gets no omni map
 * but an orthographic one fitted to the scene (shadow_sun_fit). Its
 * importance is the radius in pixels of that sphere on screen (seed 002:
 * attenuation distance and distance to the camera); with tile "auto" each
 * face gets the nearest power of two to it, within min_tile..max_tile.
 * When the six faces of every such light do not fit the atlas, the least
 * important lights shrink first, down to min_tile, and then lose their
 * shadows, least important first; those are reported (overflow
 * "drop_report") or the frame fails naming them ("fail"). The faces are
 * packed as power-of-two tiles (common/pow2_atlas.h: largest first, Z-order).
 *
 * The cubes layout (one cube map per light, every face tile x tile, the
 * same memory bound) takes lights in order of importance until the
 * array's layers run out.
 *
 * A plan belongs to one thread; planning a frame never allocates. */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/lighting/look_lighting.h"
#include "daemon/scene/scene.h"
#include "common/pow2_atlas.h"

enum shadow_status {
    SHADOW_CULLED,     /* its light reaches nothing on screen */
    SHADOW_NO_CASTERS, /* nothing within its radius can cast a shadow */
    SHADOW_MAPPED,
    SHADOW_DROPPED,    /* needed a map, but the atlas was full */
    SHADOW_DIRECTIONAL, /* a directional light: no omni map; its own orthographic map
                           (shadow_sun_fit), or unshadowed past SHADOW_MAX_SUNS */
};

struct shadow_light_plan {
    int status;       /* enum shadow_status */
    int size;         /* face edge in texels (0 unless mapped) */
    int x[6], y[6];   /* atlas: each face's corner; cubes: x[0] is the array layer */
    float importance; /* radius on screen in pixels; 0 when culled */
    float pos[3];     /* where the light is this frame */
};

struct shadow_plan {
    int lights;
    struct shadow_light_plan *light;
    int layers; /* cubes: layers of the cube map array */
    /* This frame. */
    int mapped, culled, no_casters, dropped, directional;
    double texels; /* atlas texels the faces cover */
    /* Scratch, sized at init. */
    int *order, *sizes, *slots;
    struct atlas_tile *tiles;
};

/* Sizes everything for `lights` lights; false when out of memory. */
bool shadow_plan_init(struct shadow_plan *p, int lights, const struct shadow_spec *spec);
void shadow_plan_finish(struct shadow_plan *p);

/* Plans frame (camera and lights as the scene has them then). False, with
 * err naming the lights that lost their shadows, when overflow is "fail"
 * and the atlas could not hold them. Never allocates. */
bool shadow_plan_frame(struct shadow_plan *p, const struct scene *s, const struct shadow_spec *spec,
                       int64_t frame, char *err, size_t errlen);

/* Directional lights' maps (a layer each of one depth texture array, the
 * first SHADOW_MAX_SUNS directional lights by index; any further ones stay
 * unshadowed and are counted): an orthographic projection along the
 * light, fitted to the scene's bounds (every instance's bounding sphere),
 * so that every caster and receiver lies inside it. The map is
 * shadow_sun_size texels square. */
enum { SHADOW_MAX_SUNS = 4 };
int shadow_sun_size(const struct shadow_spec *spec);

/* The fitted projection of a light shining along unit dir over box b
 * (column-major, clip z in [-1, 1] from the side the light comes from),
 * with the world size of one texel of a size-texel map and the depth range
 * in world units (for the bias, which is in world units). */
void shadow_sun_fit(const struct scene_box *b, const float dir[3], int size, float view_proj[16],
                    float *texel_world, float *depth_range);

/* Whether a spot light's cone (unit axis, outer half-angle's cosine) may
 * reach cube face f's frustum widened by w: the shadow pass draws only
 * those faces of a spot's map (conservative: the faces holding any
 * direction inside the cone always pass). */
bool shadow_cone_meets_face(const float axis[3], float cos_outer, int f, float w);

/* Cube faces per layer that the layout's memory bound allows. */
int shadow_cube_layers(const struct shadow_spec *spec, int lights);

/* The perspective's widening for a face of `size` texels with a border of
 * `border` texels on every side: the face's 90 degrees then fill the
 * inner size - 2 border texels, and filtering near an edge reads the
 * border instead of the next face's tile. */
float shadow_face_widen(int size, int border);

/* The border a filter of radius pcf needs: its taps plus the bilinear one. */
int shadow_border(int pcf);

#endif
