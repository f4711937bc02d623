#ifndef SHADEBENCH_TEAPOT_H
#define SHADEBENCH_TEAPOT_H

/* The Utah teapot (Newell 1975), tessellated in code from its public-domain
 * Bezier data: 32 bicubic patches over 306 control points (rim, body,
 * handle, spout, lid and the later-added bottom). GL-free; pure functions
 * and caller-owned meshes, so any thread.
 *
 * The mesh is y-up, centred on its bounding box and scaled by `scale` (the
 * data's height is 3.15). Each patch is one UV chart, a cell of an 8 x 4
 * grid that its triangles cover completely (object-space lighting's
 * requirement, see mesh.h). Triangles are counter-clockwise seen from
 * outside, normals point outwards.
 *
 * What "closed" means here (tests/unit/test_teapot.c checks each point):
 * after welding the patches' coincident vertices, every edge is shared by
 * at most two triangles and consistently oriented; the edges used once form
 * exactly the data's known open boundaries: the spout's mouth, and the
 * spout's and handle's ends, which sink into the body without being joined
 * to it (Newell's teapot was never a solid). Rim, body, lid and bottom
 * close up among themselves except where the lid sits on the rim: the
 * lid's outer edge (radius 1.3 at height 2.4) and the rim's inner edge
 * (radius 1.4) are separate circles, a seam the data has always had. */

#include <stdbool.h>

#include "daemon/scene/mesh.h"

#define TEAPOT_PATCH_COUNT 32
#define TEAPOT_CONTROL_POINTS 306
#define TEAPOT_HEIGHT 3.15        /* the data's height, bottom to lid knob */
#define TEAPOT_MIN_SEGMENTS 1
#define TEAPOT_MAX_SEGMENTS 64

enum teapot_part {
    TEAPOT_RIM, TEAPOT_BODY, TEAPOT_HANDLE, TEAPOT_SPOUT, TEAPOT_LID, TEAPOT_BOTTOM,
    TEAPOT_PART_COUNT
};
extern const char *const teapot_part_names[]; /* "rim", "body", ... */

enum teapot_part teapot_patch_part(int patch);

/* Position and outward unit normal of patch at (u, v) in [0, 1]^2, in the
 * mesh's frame (y-up, centred) at scale 1. */
void teapot_eval(int patch, double u, double v, double pos[3], double normal[3]);

/* Each patch cut into segments x segments quads (two triangles each):
 * 32 (segments + 1)^2 vertices, 64 segments^2 triangles. False when out of
 * memory or segments is outside TEAPOT_MIN_SEGMENTS..TEAPOT_MAX_SEGMENTS. */
bool mesh_create_teapot(struct mesh *out, int segments, float scale);

/* The largest distance between the surface and its flat triangles for a
 * tessellation into segments (sampled at every triangle's edge midpoints
 * and centroid), at scale 1: the teapot's counterpart of the sphere's
 * silhouette error. Costs 32 (8 segments)^2 patch evaluations. */
double teapot_tessellation_error(int segments);

/* The coarsest tessellation whose error, at `pixels_per_unit` pixels per
 * object-space unit (scale folded in), stays within bound_px
 * (TEAPOT_MAX_SEGMENTS when none does). */
int teapot_auto_segments(double pixels_per_unit, double bound_px);

#endif
