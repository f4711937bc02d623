#ifndef SHADEBENCH_JSON_FIELDS_H
#define SHADEBENCH_JSON_FIELDS_H

/* The validation toolkit every JSON spec parser uses (jobs, scenes,
 * technique options, sweeps): typed getters that leave the default in place
 * when a key is absent, and rejections that name the field (a dotted path)
 * and the rule it broke. GL-free; any thread. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

/* A rejection names the offending field (dotted path) and the rule it broke. */
struct job_error {
    char field[64];
    char message[256];
};

/* Fills err (field and formatted message, each cut to its buffer at a
 * UTF-8 boundary, bytes that are not UTF-8 escaped); returns false, for
 * "return job_error_set(...)". */
bool job_error_set(struct job_error *err, const char *field, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* The longest prefix of s of at most max bytes that cuts no UTF-8 sequence. */
size_t jf_utf8_prefix(const char *s, size_t max);

/* Makes s (a string in a buffer of cap bytes) valid UTF-8: a byte that
 * starts no valid sequence becomes the text \xNN, and a sequence cut short
 * at the end is dropped. Stays within cap. */
void jf_utf8_sanitize(char *s, size_t cap);

/* {"error": {"field": ..., "message": ...}}, sanitized as above so that it
 * is always built. New reference. */
json_t *job_error_to_json(const struct job_error *err);

/* Rejects keys of obj not in known (NULL-terminated), suggesting the closest
 * known key for typos; prefix is the object's path with a trailing dot. */
bool jf_check_keys(const json_t *obj, const char *prefix, const char *const *known,
                   struct job_error *err);

/* Each getter leaves *out untouched when key is absent. Integers accept 300.0
 * but never 300.5. */
bool jf_get_int(const json_t *obj, const char *key, const char *field, long min, long max,
                int *out, struct job_error *err);
bool jf_get_number(const json_t *obj, const char *key, const char *field, double min,
                   double max, double *out, struct job_error *err);
bool jf_get_bool(const json_t *obj, const char *key, const char *field, bool *out,
                 struct job_error *err);
bool jf_get_object(const json_t *obj, const char *key, const char *field, json_t **out,
                   struct job_error *err);
/* A string from choices (NULL-terminated); *out gets its index. */
bool jf_get_choice(const json_t *obj, const char *key, const char *field,
                   const char *const *choices, int *out, struct job_error *err);

/* The numbers of a JSON text (as sent, before jansson reads it): false,
 * naming the value's path, for one whose digits are not all zero that a
 * double cannot hold (1e-400 would be read as 0, which an integer field
 * would take). */
bool jf_check_numbers(const char *text, size_t len, struct job_error *err);

/* Sets value (a reference it takes) at a dotted path ("a.b.c") inside obj,
 * making the objects between and replacing what is not an object. */
void jf_set_path(json_t *obj, const char *path, json_t *value);

/* "a", "b" and "c" as `"a", "b", "c"` into buf, for rule messages. */
void jf_list_choices(const char *const *choices, char *buf, size_t cap);

#endif
