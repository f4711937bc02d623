/* The floor every technique's cost is compared with: forward's geometry and
 * passes with a flat per-object colour and no lighting (unlit.frag). */
#include "daemon/techniques/shared/single_pass.h"

extern const struct technique_info unlit_info;

static bool unlit_create(const struct technique_env *env, void **state, char *err, size_t errlen)
{
    return single_pass_create(env, "unlit", "unlit.frag", state, err, errlen);
}

const struct technique technique_unlit = {
    .info = &unlit_info,
    .create = unlit_create,
    .render = single_pass_render,
    .destroy = single_pass_destroy,
};
