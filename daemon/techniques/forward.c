/* Forward shading, the thesis's ForwardProg: one pass, every light for every
 * fragment. The reference every other technique is scored against. */
#include "daemon/techniques/technique.h"

static const char *const passes[] = {"shading", NULL};

static const struct technique_info forward_info = {
    .name = "forward",
    .summary = "one pass; every light evaluated per fragment (thesis ForwardProg)",
    .passes = passes,
};

static bool forward_create(const struct technique_env *env, void **state, char *err,
                           size_t errlen)
{
    return single_pass_create(env, "forward", "forward.frag", state, err, errlen);
}

const struct technique technique_forward = {
    .info = &forward_info,
    .create = forward_create,
    .render = single_pass_render,
    .destroy = single_pass_destroy,
};
