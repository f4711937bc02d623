/* The GL half of the registry, generated from registry.mk like the GL-free
 * half (catalog.c): each line there names a folder daemon/techniques/NAME/
 * whose GL half defines technique_NAME. Nothing else lists techniques. */
#include "daemon/techniques/technique.h"

#include <stdio.h>
#include <string.h>

#include "daemon/effects/post_spec.h"
#include "daemon/techniques/catalog.h"

/* The timer's sections hold a technique's passes, the post chain's and the
 * resolve: the GL-free budgets must agree with the timer. */
_Static_assert(TECHNIQUE_MAX_PASSES + POST_MAX_PASSES + 1 <= GPU_MAX_PASSES,
               "the technique and post pass budgets do not fit the GPU timer");

#define REGISTERED(name) extern const struct technique technique_##name;
#include "daemon/techniques/registered.h"
#undef REGISTERED

const struct technique *const technique_registry[] = {
#define REGISTERED(name) &technique_##name,
#include "daemon/techniques/registered.h"
#undef REGISTERED
    NULL,
};

const struct technique *technique_find(const char *name)
{
    for (const struct technique *const *t = technique_registry; *t; t++)
        if (strcmp((*t)->info->name, name) == 0)
            return *t;
    return NULL;
}

int technique_pass_count(const struct technique *t)
{
    int n = 0;
    while (t->info->passes && t->info->passes[n])
        n++;
    return n;
}

bool technique_check(const struct technique *t, char *err, size_t errlen)
{
    const struct technique_info *i = t->info;
    if (!i || !t->create || !t->render || !t->destroy) {
        snprintf(err, errlen, "technique %s: info, create, render and destroy are mandatory",
                 i && i->name ? i->name : "(unnamed)");
        return false;
    }
    return true;
}

bool technique_registry_check(char *err, size_t errlen)
{
    int i = 0;
    for (; technique_registry[i]; i++) {
        if (!technique_check(technique_registry[i], err, errlen))
            return false;
        if (technique_registry[i]->info != technique_infos[i]) {
            snprintf(err, errlen, "technique %s: its GL half points at another info than the "
                     "registry's", technique_infos[i] ? technique_infos[i]->name : "(none)");
            return false;
        }
    }
    if (technique_infos[i]) {
        snprintf(err, errlen, "technique %s: registered without a GL half", technique_infos[i]->name);
        return false;
    }
    return true;
}
