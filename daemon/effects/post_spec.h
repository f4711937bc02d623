#ifndef SHADEBENCH_POST_SPEC_H
#define SHADEBENCH_POST_SPEC_H

/* A look's post chain as a job states it (look.post): an ordered list of
 * registered effects, each with its options; parsing with errors naming the
 * entry ("look.post[1].radius"), the JSON written back, the labels and pass
 * names the chain runs under. GL-free; any thread. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "common/json_fields.h"
#include "common/options.h"
#include "daemon/effects/effect_info.h"

/* Effects one look may chain. */
#define POST_MAX_EFFECTS 8
/* Timed passes a chain may add: the timer's 32 sections hold a technique's
 * 16, the chain's and the harness's resolve. */
#define POST_MAX_PASSES 15
/* Room for a pass name with its instance label: "bloom2.composite". */
#define POST_PASS_NAME_BYTES 40

/* One effect of a chain and its options (the effect's struct, by bytes). */
struct post_effect {
    int effect; /* index into effect_infos */
    struct opt_values options;
};

struct post_spec {
    int count;
    struct post_effect effects[POST_MAX_EFFECTS];
};

/* Reads an ordered list: each entry a name ("bloom") or an object with one
 * key, the name, holding its options ({"bloom": {"radius": 8}}). Errors
 * name the entry's path under field: "look.post[1].radius". */
bool post_spec_parse(const json_t *list, const char *field, struct post_spec *out,
                     struct job_error *err);

/* [{"bloom": {...every option...}}, ...]. New reference. */
json_t *post_spec_to_json(const struct post_spec *p);

/* Options of entry i, typed by its effect's struct. */
static inline const void *post_effect_options(const struct post_spec *p, int i)
{
    return p->effects[i].options.bytes;
}

/* The label of entry i: the effect's name, numbered from the second
 * instance of the same effect on ("bloom", "toon", "bloom2"), so that pass
 * names stay unique in results. */
void post_effect_label(const struct post_spec *p, int i, char *buf, size_t cap);

/* Every pass the chain runs, in frame order, as "<label>.<pass>" into names
 * (cap entries); returns how many the chain needs (which may exceed cap). */
int post_spec_pass_names(const struct post_spec *p, char (*names)[POST_PASS_NAME_BYTES], int cap);

/* What the chain needs of time: every effect's needs merged into out
 * (which the caller starts, zeroed or with the technique's). */
void post_spec_needs(const struct post_spec *p, struct frame_needs *out);

/* Drops the entries whose effect anti-aliases (EFFECT_ANTIALIASING): the
 * chain a supersampled reference renders. Returns how many it dropped. */
int post_spec_drop_antialiasing(struct post_spec *p);

#endif
