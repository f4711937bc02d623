#define _POSIX_C_SOURCE 200809L
#include "daemon/effects/effect_info.h"

#include <stdio.h>
#include <string.h>

/* The GL-free half of the registry: generated from registry.mk, one
 * REGISTERED(NAME) line per effect in its order, each naming the NAME_info
 * its folder defines. */
#define REGISTERED(name) extern const struct effect_info name##_info;
#include "daemon/effects/registered.h"
#undef REGISTERED

const struct effect_info *const effect_infos[] = {
#define REGISTERED(name) &name##_info,
#include "daemon/effects/registered.h"
#undef REGISTERED
    NULL,
};

int effect_find(const char *name)
{
    for (int i = 0; effect_infos[i]; i++)
        if (strcmp(effect_infos[i]->name, name) == 0)
            return i;
    return -1;
}

json_t *effect_catalog_json(void)
{
    json_t *list = json_array();
    for (int i = 0; effect_infos[i]; i++) {
        const struct effect_info *e = effect_infos[i];
        json_array_append_new(list, opt_part_json(e->name, e->summary, e->passes, &e->options));
    }
    return list;
}

bool effect_infos_check(char *err, size_t errlen)
{
    for (int i = 0; effect_infos[i]; i++) {
        const struct effect_info *e = effect_infos[i];
        int passes = 0;
        while (e->passes && e->passes[passes])
            passes++;
        if (i >= EFFECT_REGISTRY_MAX || !e->name || !e->name[0] || !e->summary ||
            !e->active_passes || passes < 1 || effect_find(e->name) != i) {
            snprintf(err, errlen, "effect %s: a unique name, a summary, passes and "
                     "active_passes are mandatory, and at most %d effects",
                     e->name ? e->name : "(unnamed)", EFFECT_REGISTRY_MAX);
            return false;
        }
        if (e->options.size > OPT_MAX_BYTES) {
            snprintf(err, errlen, "effect %s: options take %zu bytes; %d fit in a chain",
                     e->name, e->options.size, OPT_MAX_BYTES);
            return false;
        }
        char owner[48];
        snprintf(owner, sizeof(owner), "effect %s", e->name);
        if (!opt_table_check(&e->options, owner, err, errlen))
            return false;
    }
    return true;
}
