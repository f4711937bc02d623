#ifndef SHADEBENCH_TECHNIQUE_INFO_H
#define SHADEBENCH_TECHNIQUE_INFO_H

/* The GL-free half of a technique: its name, summary, named passes and
 * options (defaults, ranges, parsing with field-naming errors, JSON, what a
 * sweep may vary). The job parser, sweeps, reports and /v1/info read these
 * from a catalogue handed to them, so adding a technique changes nothing in
 * jobs, sweeps or HTTP. The GL half (technique.h) points at its info.
 *
 * Options are declared as a table over the technique's own options struct;
 * one generic parser reads every technique's object ("osl": {...}) with it,
 * so every technique answers bad input the same way. Any thread. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "common/json_fields.h"

/* Bytes of one technique's options struct, stored inline in a job spec. */
#define TECHNIQUE_OPTIONS_BYTES 256
/* Techniques a catalogue may hold. */
#define TECHNIQUE_MAX 32
/* Named passes a technique may declare (the harness adds its own). */
#define TECHNIQUE_MAX_PASSES 16

enum topt_type {
    TOPT_INT,          /* int; min..max */
    TOPT_NUMBER,       /* double; min..max */
    TOPT_BOOL,         /* bool */
    TOPT_CHOICE,       /* int index into choices */
    TOPT_POW2_OR_AUTO, /* int: a power of two in min..max, or 0 for "auto" */
    TOPT_INT_LIST,     /* int[count], each in min..max */
};

struct technique_option {
    const char *name;    /* within the technique; dots nest: "gbuffer.normal" */
    enum topt_type type;
    const char *summary;
    double def, min, max;          /* def: the value, choice index, or 0 for auto */
    const char *const *choices;    /* TOPT_CHOICE, NULL-terminated */
    const int *def_list;           /* TOPT_INT_LIST defaults */
    int count;                     /* TOPT_INT_LIST length */
    size_t offset;                 /* into the options struct */
};

struct technique_info {
    const char *name;
    const char *summary;
    /* The passes a frame runs, in order, NULL-terminated; each is timed and
     * shown in debug captures under this name. */
    const char *const *passes;
    /* Terminated by an entry with name NULL; NULL for none. */
    const struct technique_option *options;
    size_t options_size; /* <= TECHNIQUE_OPTIONS_BYTES */
    /* Rules across fields, after every field parsed; may be NULL. field_prefix
     * is "<name>." for errors. */
    bool (*check)(const void *opts, struct job_error *err);
};

/* A technique's options, stored in a job spec without knowing their type. */
struct technique_options {
    _Alignas(max_align_t) unsigned char bytes[TECHNIQUE_OPTIONS_BYTES];
};

struct technique_catalog {
    const struct technique_info *infos[TECHNIQUE_MAX];
    int count;
};

/* Adds info; false when the catalogue is full or its options do not fit. */
bool technique_catalog_add(struct technique_catalog *c, const struct technique_info *info);
/* Index of name, or -1. */
int technique_catalog_find(const struct technique_catalog *c, const char *name);
/* "forward", "unlit", ... for rule messages. */
void technique_catalog_list(const struct technique_catalog *c, char *buf, size_t cap);
/* /v1/info's "techniques": every technique with its passes and options
 * (type, default, range or choices, summary). New reference. */
json_t *technique_catalog_json(const struct technique_catalog *c);

void technique_options_defaults(const struct technique_info *t, struct technique_options *o);
/* Applies the technique's JSON object over o (defaults first); errors name
 * "<technique>.<option>". */
bool technique_options_parse(const struct technique_info *t, const json_t *obj,
                             struct technique_options *o, struct job_error *err);
/* Every option, defaults filled in. New reference. */
json_t *technique_options_to_json(const struct technique_info *t, const struct technique_options *o);

/* The option at a dotted path ("osl.texel_density"), for sweeps; NULL when
 * the path names no option of a catalogued technique. */
const struct technique_option *technique_catalog_option(const struct technique_catalog *c,
                                                        const char *path);

#endif
