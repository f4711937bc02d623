#ifndef SHADEBENCH_SCENE_MATH_H
#define SHADEBENCH_SCENE_MATH_H

/* Leaf helpers shared by the files of daemon/scene (and the frustum test
 * the rest of the daemon uses through scene.h). Pure functions; any
 * thread. */

#include <stdbool.h>
#include <stdint.h>

/* A fixed integer hash to [0, 1): the scene's only source of "randomness",
 * so that every build of a spec is bit-identical. salt picks a stream. */
double scene_hash01(uint32_t index, uint32_t salt);
/* Van der Corput radical inverse of i in base. */
double scene_radical_inverse(unsigned i, unsigned base);
void scene_hsv_to_rgb(double h, double s, double v, float out[3]);

/* True when the sphere (centre, radius) lies at least partly inside the
 * frustum of view_proj (inside: fully == false), or entirely inside it. */
bool scene_sphere_in_frustum(const float view_proj[16], const float centre[3], float radius,
                             bool fully);

#endif
