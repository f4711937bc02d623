#ifndef SHADEBENCH_OPTIONS_H
#define SHADEBENCH_OPTIONS_H

/* Option tables: how every part of a job that has options declares them (a
 * technique, a post effect, the look, its image-based lighting and its
 * shadows). A table lists each option of the part's own options struct
 * (offsetof), with its type, default, range or choices and a summary; one
 * generic reader applies a JSON object to that struct, naming the field and
 * the rule it broke (and the closest name, for a typo), so that every part
 * answers bad input alike; the same table writes the struct back as JSON
 * and describes it for /v1/info.
 *
 * Dotted names nest: "gbuffer.normal" is read from {"gbuffer": {"normal":
 * ...}}, and a job may as well write {"gbuffer.normal": ...}, as /v1/info
 * lists it; giving both is refused, naming the option. Errors always name
 * the dotted path under the part's prefix ("<technique>.gbuffer.normal").
 *
 * GL-free. Tables are immutable: any thread. */

#include <jansson.h>
#include <stdalign.h>
#include <stdbool.h>
#include <stddef.h>

#include "common/json_fields.h"

/* Bytes of options a part may keep inline (in a job spec, a post chain). */
#define OPT_MAX_BYTES 256
/* Options one table may declare. */
#define OPT_MAX_FIELDS 48

enum opt_type {
    OPT_INT,          /* int; min..max (300.0 is read as 300, 300.5 refused) */
    OPT_NUMBER,       /* double; finite, min..max */
    OPT_BOOL,         /* bool */
    OPT_CHOICE,       /* int: index into choices */
    OPT_POW2,         /* int: a power of two in min..max */
    OPT_POW2_OR_AUTO, /* int: a power of two in min..max, or 0 for "auto" */
    OPT_INT_LIST,     /* int[count], each in min..max */
    OPT_CUSTOM,       /* JSON no generic type reads: the field's own hooks */
};

/* The hooks of an OPT_CUSTOM option. They see the whole options struct, so
 * that one JSON value may fill several members (a probe count or list). */
struct opt_hooks {
    /* Sets the option's members to their defaults; NULL leaves them zero. */
    void (*defaults)(void *opts);
    /* Reads v (present) into opts; errors name field. */
    bool (*parse)(const json_t *v, const char *field, void *opts, struct job_error *err);
    /* The option's value. New reference. */
    json_t *(*to_json)(const void *opts);
    const char *type; /* for /v1/info: "object", "list", ... */
    const char *rule; /* for /v1/info */
};

struct opt_field {
    const char *name; /* dots nest: "gbuffer.normal"; NULL ends a table */
    enum opt_type type;
    const char *summary;
    double def, min, max;        /* def: the value, the choice's index, or 0 for "auto" */
    const char *const *choices;  /* OPT_CHOICE, NULL-terminated */
    const int *def_list;         /* OPT_INT_LIST defaults */
    int count;                   /* OPT_INT_LIST length */
    const char *auto_means;      /* OPT_POW2_OR_AUTO: what "auto" does, for the rule text */
    const struct opt_hooks *hooks; /* OPT_CUSTOM */
    size_t offset;               /* into the options struct */
};

struct opt_table {
    const struct opt_field *fields; /* NULL: no options */
    size_t size;                    /* of the options struct: at most OPT_MAX_BYTES */
    /* Rules across fields, after every field was read; may complete the
     * options (a default that depends on another). prefix is the part's
     * path ("<technique>", "look.shadows"), for the field an error
     * names. May be NULL. */
    bool (*check)(void *opts, const char *prefix, struct job_error *err);
};

/* A part's options kept without knowing their type (a job's techniques, a
 * chain's effects). */
struct opt_values {
    alignas(max_align_t) unsigned char bytes[OPT_MAX_BYTES];
};

/* Zeroes opts (t->size bytes), then sets every default. */
void opt_defaults(const struct opt_table *t, void *opts);

/* Reads the JSON object obj over opts (which hold defaults or earlier
 * values), then runs the table's check. Errors name "<prefix>.<option>";
 * obj that is not an object is refused naming prefix. */
bool opt_parse(const struct opt_table *t, const json_t *obj, const char *prefix, void *opts,
               struct job_error *err);

/* Reads one option's value v into opts, errors naming field; no check
 * across fields. For a field a job may give elsewhere too (an alias). */
bool opt_parse_value(const struct opt_field *f, const json_t *v, const char *field, void *opts,
                     struct job_error *err);

/* Every option, nested by its dotted name. New reference. */
json_t *opt_to_json(const struct opt_table *t, const void *opts);

/* /v1/info's description of the options: by dotted name, each with its
 * type, default, rule, summary, and its choices or range. New reference. */
json_t *opt_describe(const struct opt_table *t);

/* /v1/info's entry of a part with options (a technique, an effect): name,
 * summary, the passes it may run, options as opt_describe. New reference. */
json_t *opt_part_json(const char *name, const char *summary, const char *const *passes,
                      const struct opt_table *t);

/* The option of that dotted name, or NULL. */
const struct opt_field *opt_find(const struct opt_table *t, const char *name);

/* Checks a table at registration: names unique and not both an option and
 * a group, every member inside the struct, the struct within
 * OPT_MAX_BYTES, choices and hooks present, defaults within the rules.
 * err starts with owner ("technique <name>"). */
bool opt_table_check(const struct opt_table *t, const char *owner, char *err, size_t errlen);

#endif
