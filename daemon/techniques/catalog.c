#define _POSIX_C_SOURCE 200809L
#include "daemon/techniques/catalog.h"

#include <stdio.h>
#include <string.h>

/* The GL-free half of the registry: generated from registry.mk, one
 * REGISTERED(NAME) line per technique in its order, each naming the
 * NAME_info its folder defines. */
#define REGISTERED(name) extern const struct technique_info name##_info;
#include "daemon/techniques/registered.h"
#undef REGISTERED

const struct technique_info *const technique_infos[] = {
#define REGISTERED(name) &name##_info,
#include "daemon/techniques/registered.h"
#undef REGISTERED
    NULL,
};

static void catalog_empty(struct technique_catalog *c)
{
    memset(c, 0, sizeof(*c));
    c->baseline = -1;
}

/* A name is a JSON key of the job and a path component of sweeps. */
static bool name_ok(const char *name)
{
    size_t len = name ? strlen(name) : 0;
    if (len == 0 || len > 31)
        return false;
    for (size_t i = 0; i < len; i++)
        if (!((name[i] >= 'a' && name[i] <= 'z') || (name[i] >= '0' && name[i] <= '9') ||
              name[i] == '_'))
            return false;
    return true;
}

static bool info_check(const struct technique_info *t, char *err, size_t errlen)
{
    if (!t || !name_ok(t->name) || !t->summary) {
        snprintf(err, errlen, "technique %s: a name of 1 to 31 characters of a-z, 0-9 and '_', "
                 "and a summary, are mandatory", t && t->name ? t->name : "(unnamed)");
        return false;
    }
    int passes = 0;
    while (t->passes && t->passes[passes])
        passes++;
    if (passes < 1 || passes > TECHNIQUE_MAX_PASSES) {
        snprintf(err, errlen, "technique %s: declares %d passes; 1 to %d allowed", t->name,
                 passes, TECHNIQUE_MAX_PASSES);
        return false;
    }
    if (t->options.size > TECHNIQUE_OPTIONS_BYTES) {
        snprintf(err, errlen, "technique %s: options take %zu bytes; %d fit in a job", t->name,
                 t->options.size, TECHNIQUE_OPTIONS_BYTES);
        return false;
    }
    char owner[48];
    snprintf(owner, sizeof(owner), "technique %s", t->name);
    return opt_table_check(&t->options, owner, err, errlen);
}

bool technique_catalog_add(struct technique_catalog *c, const struct technique_info *info,
                           char *err, size_t errlen)
{
    if (!info_check(info, err, errlen))
        return false;
    if (c->count >= TECHNIQUE_MAX || technique_catalog_find(c, info->name) >= 0) {
        snprintf(err, errlen, "technique %s: registered twice, or more than %d techniques",
                 info->name, TECHNIQUE_MAX);
        return false;
    }
    if (c->baseline < 0 && (info->flags & TECHNIQUE_BASELINE))
        c->baseline = c->count;
    c->infos[c->count++] = info;
    return true;
}

bool technique_catalog_init(struct technique_catalog *c, char *err, size_t errlen)
{
    catalog_empty(c);
    for (const struct technique_info *const *t = technique_infos; *t; t++)
        if (!technique_catalog_add(c, *t, err, errlen))
            return false;
    return true;
}

int technique_catalog_find(const struct technique_catalog *c, const char *name)
{
    for (int i = 0; i < c->count; i++)
        if (strcmp(c->infos[i]->name, name) == 0)
            return i;
    return -1;
}

void technique_catalog_list(const struct technique_catalog *c, unsigned having, char *buf,
                            size_t cap)
{
    size_t used = 0;
    buf[0] = '\0';
    for (int i = 0; i < c->count && used < cap; i++)
        if ((c->infos[i]->flags & having) == having)
            used += (size_t)snprintf(buf + used, cap - used, "%s\"%s\"", used ? ", " : "",
                                     c->infos[i]->name);
}

json_t *technique_catalog_json(const struct technique_catalog *c)
{
    json_t *list = json_array();
    for (int i = 0; i < c->count; i++) {
        const struct technique_info *t = c->infos[i];
        json_array_append_new(list, opt_part_json(t->name, t->summary, t->passes, &t->options));
    }
    return list;
}

const struct opt_field *technique_catalog_option(const struct technique_catalog *c,
                                                 const char *path)
{
    const char *dot = strchr(path, '.');
    if (!dot)
        return NULL;
    for (int i = 0; i < c->count; i++) {
        size_t len = strlen(c->infos[i]->name);
        if ((size_t)(dot - path) == len && strncmp(path, c->infos[i]->name, len) == 0)
            return opt_find(&c->infos[i]->options, dot + 1);
    }
    return NULL;
}
