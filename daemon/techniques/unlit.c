/* The floor every technique's cost is compared with: forward's geometry and
 * passes with a flat per-object colour and no lighting. */
#include "daemon/techniques/technique.h"

static const char *const sections[] = {"frame", NULL};

static bool unlit_create(const struct technique_ctx *ctx, void **state,
                         char *err, size_t errlen)
{
    return single_pass_create(ctx, "unlit", "unlit.frag", state, err, errlen);
}

const struct technique technique_unlit = {
    .name = "unlit",
    .summary = "forward's geometry and passes, flat colour, no lights: the cost floor",
    .sections = sections,
    .create = unlit_create,
    .render = single_pass_render,
    .describe = NULL,
    .destroy = single_pass_destroy,
};
