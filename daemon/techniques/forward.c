/* Forward shading, the thesis's ForwardProg: one pass, every light for every fragment. */
#include "daemon/techniques/technique.h"

static const char *const sections[] = {"frame", NULL};

static bool forward_create(const struct technique_ctx *ctx, void **state,
                           char *err, size_t errlen)
{
    return single_pass_create(ctx, "forward", "forward.frag", state, err, errlen);
}

const struct technique technique_forward = {
    .name = "forward",
    .summary = "one pass; every light evaluated per fragment (thesis ForwardProg)",
    .sections = sections,
    .create = forward_create,
    .render = single_pass_render,
    .describe = NULL,
    .destroy = single_pass_destroy,
};
