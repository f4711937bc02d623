#ifndef SHADEBENCH_OSL_INFO_H
#define SHADEBENCH_OSL_INFO_H

/* OSL's GL-free half: its options ("osl": {...} in a job, async_distance
 * included) and description. Any thread. */

#include "daemon/techniques/technique_info.h"

enum osl_reshade {
    OSL_RESHADE_TOUCHED, /* only objects a moving light reaches */
    OSL_RESHADE_ALL,     /* every due object, lit by a moving light or not */
};

enum osl_visibility {
    OSL_VISIBILITY_ALL,  /* shade whole tiles (the thesis) */
    OSL_VISIBILITY_SEEN, /* shade the atlas blocks the last frame sampled, and their neighbours */
};

struct osl_options {
    int resolution; /* tile edge in texels; 0 means "auto" */
    double texel_density;
    int reshade;    /* enum osl_reshade */
    /* Async shading (thesis 3.1.2.3): an object at camera distance r is
     * reshaded every floor(r / async_distance) + 1 frames; 0 every frame. */
    double async_distance;
    int visibility; /* enum osl_visibility */
    /* With visibility "seen": at most this many texels shaded a frame
     * (whole 8x8 blocks, chosen by priority), 0 for no limit. */
    int budget_texels;
    /* With visibility "seen": an object keeps its shading while the bound
     * on the radiance change its lights' motion can cause stays at or
     * below this (osl_change.h); 0 reshades whenever its schedule says. */
    double change_threshold;
};

extern const struct technique_info osl_info;

#endif
