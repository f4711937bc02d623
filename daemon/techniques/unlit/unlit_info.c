/* The unlit floor's GL-free half: no options, one pass. */
#include "daemon/techniques/technique_info.h"

static const char *const passes[] = {"shading", NULL};

const struct technique_info unlit_info = {
    .name = "unlit",
    .summary = "forward's geometry and passes, flat colour, no lights: the cost floor",
    .passes = passes,
    .flags = TECHNIQUE_READS_NO_LIGHT,
};
