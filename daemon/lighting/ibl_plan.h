#ifndef SHADEBENCH_IBL_PLAN_H
#define SHADEBENCH_IBL_PLAN_H

/* Where the light probes stand and which of them light a frame (GL-free;
 * the harness captures and filters them, daemon/look/ibl.c).
 *
 * Placement: the spec's list, or n probes on a grid over the objects'
 * footprint, just above the tallest object (so no probe starts inside an
 * object), each reaching over its cell and its neighbours'.
 * Selection (seed 002): a probe's importance for the camera is its radius
 * over its distance to the eye; the `blend` most important probes are the
 * frame's, and the shader weights each by its own falloff at the shaded
 * point, the environment taking what they leave. Pure functions; any
 * thread. */

#include "daemon/lighting/look_lighting.h"
#include "daemon/scene/scene.h"

struct ibl_probe {
    float pos[3];
    float radius;
};

/* spec->probes probes into out. */
void ibl_place_probes(const struct scene *s, const struct ibl_spec *spec, struct ibl_probe *out);

/* The (at most) blend most important of n probes for an eye, most
 * important first, ties by index; returns how many. */
int ibl_select(const struct ibl_probe *probes, int n, const float eye[3], int blend, int *out);

/* A probe's weight at point p before normalisation: 1 at its centre,
 * falling smoothly to 0 at its radius (shaders/common/ibl.glsl's falloff). */
float ibl_probe_weight(const struct ibl_probe *probe, const float p[3]);

#endif
