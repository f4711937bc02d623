#ifndef SHADEBENCH_OSL_SCHEDULE_H
#define SHADEBENCH_OSL_SCHEDULE_H

/* Which objects Object Space Lighting reshades at which frame. GL-free.
 *
 * Async shading (thesis 3.1.2.3): with async distance d > 0, an object at
 * camera distance r is due every floor(r/d) + 1 frames; objects of the same
 * period get staggered offsets so the work spreads over frames. The shading
 * shown at frame k is the shading "as of" the object's last due frame
 * s(k) <= k, lit with the lights of frame s(k), which makes every frame a
 * pure function of k however the run started. A due object is actually
 * reshaded only when a moving light reaches its bounds now or at its
 * previous due frame (otherwise the result would be the same texels). */

#include <stdbool.h>
#include <stdint.h>

#include "daemon/techniques/osl/osl_info.h"
#include "daemon/scene/scene.h"

struct osl_schedule {
    int count;
    int *period;
    int *offset;
    int max_period;
};

struct osl_work {
    int instance;
    int64_t time; /* frame whose lights this shading uses */
};

int osl_period(double distance, double async_distance);

bool osl_schedule_init(struct osl_schedule *s, const double *distances, int count,
                       double async_distance);
void osl_schedule_finish(struct osl_schedule *s);

/* Last due frame of object i at or before frame. */
int64_t osl_schedule_last(const struct osl_schedule *s, int i, int64_t frame);
bool osl_schedule_due(const struct osl_schedule *s, int i, int64_t frame);

/* True when a moving light of the (dynamic) scene reaches instance i's
 * bounds at frame: a point light by its sphere, a spot light by its cone
 * (daemon/scene/light_shape.h); a directional light never moves, so it
 * never counts. */
bool osl_touched(const struct scene *scene, int i, int64_t frame);

/* A bound on how much the lights' motion between frames from and to can
 * change the radiance (per channel) of any point of instance i, for a
 * view that does not move: the sum over the lights of
 *   min(C a (A + S),  C (A + S) 2 delta / r + C a (A + n S) delta / dmin + C a S)
 * where C is the light's largest colour channel, r its radius, delta how
 * far it moved, dmin the least distance from its path (the segment between
 * its two positions) to the object's bounding sphere, a = 1 - dmin^2/r^2
 * the largest attenuation on that path, A the object's largest albedo
 * channel, S its specular and n its shininess. The first term holds for any
 * contribution in [0, C a (A + S)] (both shadings lie there, so they differ
 * by no more). The second is Phong's: attenuation 1 - d^2/r^2 changes by at
 * most 2/r per unit of motion; the unit light vector, N.L and (through the
 * reflection) R.V by at most 1/dmin per unit; x^n by at most n per unit of
 * x (n >= 1); and C a S for the step where N.L crosses 0, which cuts a
 * specular that may not be 0 there. lipschitz false (Blinn-Phong, shadows) keeps only the first term. A
 * light farther than its radius from the object on its whole path adds 0.
 * Infinite when a light that is not a point light moved. */
double osl_change_bound(const struct scene *scene, int i, int64_t from, int64_t to,
                        bool lipschitz);

/* Objects to shade at frame; initial shades everything (first frame drawn).
 * out must hold scene->instance_count entries. Returns how many. */
int osl_schedule_plan(const struct osl_schedule *s, const struct scene *scene,
                      int64_t frame, bool initial, enum osl_reshade mode,
                      struct osl_work *out);

#endif
