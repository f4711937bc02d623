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

/* Objects to shade at frame; initial shades everything (first frame drawn).
 * out must hold scene->instance_count entries. Returns how many. */
int osl_schedule_plan(const struct osl_schedule *s, const struct scene *scene,
                      int64_t frame, bool initial, enum osl_reshade mode,
                      struct osl_work *out);

#endif
