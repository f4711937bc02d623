#ifndef SHADEBENCH_OSL_INFO_H
#define SHADEBENCH_OSL_INFO_H

/* OSL's GL-free half: its options ("osl": {...} in a job) and description.
 * Any thread. */

#include "daemon/techniques/technique_info.h"

enum osl_reshade {
    OSL_RESHADE_TOUCHED, /* only objects a moving light reaches */
    OSL_RESHADE_ALL,     /* every due object, as the thesis measured */
};

struct osl_options {
    int resolution; /* tile edge in texels; 0 means "auto" */
    double texel_density;
    int reshade;    /* enum osl_reshade */
};

extern const struct technique_info osl_info;

#endif
