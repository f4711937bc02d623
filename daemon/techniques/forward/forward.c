/* Forward shading, the thesis's ForwardProg: one pass, every light for every
 * fragment (shaders/common/forward.frag, which the look's light probes
 * capture the scene with too). The baseline every other technique is
 * scored against. */
#include "daemon/techniques/shared/single_pass.h"

extern const struct technique_info forward_info;

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
