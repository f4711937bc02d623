#ifndef SHADEBENCH_LIGHT_SHAPE_H
#define SHADEBENCH_LIGHT_SHAPE_H

/* Where a light can light (GL-free; pure functions, any thread): a point
 * light its sphere of influence, a spot light the part of that sphere
 * inside its outer cone (a spherical sector), a directional light
 * everything. The culling techniques, OSL's reshade schedule, the shadow
 * plan and scene_describe all ask these, and
 * shaders/common/light_shape.glsl mirrors them for the GPU's binning, so
 * that every one of them bounds a light the same way.
 *
 * Every test here is conservative: it may answer "reaches" for a region the
 * light does not light, never the reverse, because a culling technique that
 * leaves out a light contributing anything would no longer sum what
 * forward sums. */

#include <stdbool.h>

#include "daemon/scene/scene.h"

/* The smallest sphere holding a spherical sector: apex a, unit axis d,
 * radius (range) r, half-angle t (given as its cosine and sine, t in
 * [0, 90] degrees).
 *   t <= 45: the sphere through the apex and the rim circle (the cone's
 *            base at distance r cos t, radius r sin t) has its centre on the
 *            axis at x with x^2 = (x - r cos t)^2 + (r sin t)^2, so
 *            x = r / (2 cos t), radius r / (2 cos t); it holds the cap too
 *            (a cap point at angle p from the axis lies x^2 + r^2 - 2 x r
 *            cos p <= x^2 from the centre since cos p >= cos t).
 *   t >= 45: the rim circle's own sphere, centre a + d r cos t, radius
 *            r sin t, already holds the apex (r cos t <= r sin t) and the
 *            cap (r^2 (1 - 2 cos p cos t + cos^2 t) <= r^2 sin^2 t).
 * Both give r / sqrt 2 at 45 degrees. */
void light_cone_bound(const float apex[3], const float dir[3], float range, float cos_half,
                      float sin_half, float centre[3], float *radius);

/* Whether the spherical sector (apex, unit dir, range, half-angle) may touch
 * the sphere (c, r): Bart Wronski's "cull that cone" test (2017). It culls
 * a sphere wholly outside the infinite cone's side (the distance to it, for
 * a centre beside the apex, is cos t |V x d| - sin t (V . d), which
 * underestimates the true distance behind the apex, so it errs towards
 * keeping), wholly past the range along the axis, or wholly behind the
 * apex. */
bool light_cone_touches_sphere(const float apex[3], const float dir[3], float range,
                               float cos_half, float sin_half, const float c[3], float r);

/* The sphere bounding what light l lights from world position pos (its
 * position this frame): a point light's own sphere, a spot light's cone's
 * (light_cone_bound). False for a directional light: it lights
 * everything. */
bool scene_light_bound(const struct scene_light *l, const float pos[3], float centre[3],
                       float *radius);

/* Whether light l at pos may light anything within the sphere (c, r):
 * a directional light always; a point light when the spheres overlap
 * (strictly, as the scene's figures always counted); a spot light when its
 * bounding sphere overlaps and light_cone_touches_sphere agrees. */
bool scene_light_reaches(const struct scene_light *l, const float pos[3], const float c[3],
                         float r);

/* sin of the outer half-angle of a spot light, from its cos_outer. */
float scene_light_sin_outer(const struct scene_light *l);

/* glTF's angular falloff (KHR_lights_punctual's reference implementation):
 * with scale = 1 / max(cos_inner - cos_outer, 1e-3), t = clamp((cd -
 * cos_outer) scale, 0, 1) and the falloff t^2, cd being the cosine between
 * the spot's axis and the direction from the light to the point. Exactly 0
 * at and outside the outer cone. scene_light_cone_scale gives scale as the
 * light buffer carries it. */
float scene_light_cone_scale(const struct scene_light *l);
float scene_spot_falloff(const struct scene_light *l, float cd);

#endif
