/* The GL half of the effect registry, generated from registry.mk like the
 * GL-free half (effect_info.c): each line there names a folder
 * daemon/effects/NAME/ whose GL half defines effect_NAME. Nothing else
 * lists effects. */
#include "daemon/effects/effect.h"

#include <stdio.h>

#define REGISTERED(name) extern const struct effect effect_##name;
#include "daemon/effects/registered.h"
#undef REGISTERED

const struct effect *const effect_registry[] = {
#define REGISTERED(name) &effect_##name,
#include "daemon/effects/registered.h"
#undef REGISTERED
    NULL,
};

bool effect_registry_check(char *err, size_t errlen)
{
    if (!effect_infos_check(err, errlen))
        return false;
    int i = 0;
    for (; effect_registry[i]; i++) {
        const struct effect *e = effect_registry[i];
        if (e->info != effect_infos[i] || !e->create || !e->run || !e->destroy) {
            snprintf(err, errlen, "effect %s: its GL half needs create, run, destroy and the "
                     "registry's info", effect_infos[i] ? effect_infos[i]->name : "(none)");
            return false;
        }
    }
    if (effect_infos[i]) {
        snprintf(err, errlen, "effect %s: registered without a GL half", effect_infos[i]->name);
        return false;
    }
    return true;
}
