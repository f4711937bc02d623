#ifndef SHADEBENCH_CULLED_H
#define SHADEBENCH_CULLED_H

/* The technique hooks shared by the light-culling techniques, which differ
 * only in their geometry pass (a g-buffer, or a depth pre-pass for forward
 * shading) and their grid (screen tiles with depth bounds, or froxels):
 *   tiles:   geometry, binning, lighting or shading
 *   froxels: binning, geometry, lighting or shading
 * Tiles need the frame's depth before binning; froxels need none, so they
 * bin first and their binning time stands alone. Each such technique's info
 * declares its passes in that order under these names: "gbuffer", "edges"
 * (the MSAA edge pixels), "binning", "lighting" for the deferred ones (four),
 * "depth_prepass", "binning", "shading" for the forward ones (three);
 * culled_create finds each by its name. Deferred lighting is one
 * full-screen pass over the g-buffer; forward shading draws the objects
 * again with GL_LEQUAL against the pre-pass, so each pixel shades once.
 * Both loop over the pixel's cell (shaders/culling/light_grid.glsl). Render
 * thread only. */

#include <stdbool.h>
#include <stddef.h>

#include "daemon/techniques/shared/light_grid.h"
#include "daemon/techniques/technique.h"

struct culled_config {
    bool deferred;                  /* g-buffer and full-screen lighting, else forward */
    struct light_grid_config grid;
    struct gbuffer_options gbuffer; /* deferred only */
};

bool culled_create(const struct technique_env *env, const struct culled_config *cfg,
                   void **state, char *err, size_t errlen);
bool culled_render(void *state, const struct technique_env *env, int64_t frame, char *err,
                   size_t errlen);
json_t *culled_describe(void *state);
bool culled_verify(void *state, char *err, size_t errlen);
void culled_destroy(void *state);

#endif
