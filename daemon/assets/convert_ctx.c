#define _POSIX_C_SOURCE 200809L
/* The conversion's context and the JSON readers the stages share
 * (convert_internal.h). */
#include "daemon/assets/convert_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

bool fail(struct ctx *c, int status, const char *field, const char *fmt, ...)
{
    if (c->err->status == 0) {
        c->err->status = status;
        snprintf(c->err->field, sizeof(c->err->field), "%s", field);
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(c->err->message, sizeof(c->err->message), fmt, ap);
        va_end(ap);
    }
    return false;
}

void ignore(struct ctx *c, const char *fmt, ...)
{
    char buf[128];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof(buf), fmt, ap);
    va_end(ap);
    for (uint32_t i = 0; i < c->nignored; i++)
        if (strcmp(c->ignored[i], buf) == 0)
            return;
    if (c->nignored < MAX_IGNORED) {
        char *s = strdup(buf);
        if (s)
            c->ignored[c->nignored++] = s;
    }
}

/* ---- JSON helpers: each names the field it refuses ---- */

/* The array at key (NULL when absent); anything else there is an error. */
bool opt_array(struct ctx *c, json_t *obj, const char *key, const char *field, json_t **out)
{
    json_t *v = json_object_get(obj, key);
    *out = NULL;
    if (!v)
        return true;
    if (!json_is_array(v))
        return fail(c, 400, field, "must be an array");
    if (json_array_size(v) > MAX_ENTRIES)
        return fail(c, 422, field, "%zu entries, more than the converter takes (%d)",
                    json_array_size(v), MAX_ENTRIES);
    *out = v;
    return true;
}

/* An integer in [min, max] at key; def when absent and not required. */
bool get_int(struct ctx *c, json_t *obj, const char *key, const char *field, bool required,
                    int64_t min, int64_t max, int64_t def, int64_t *out)
{
    json_t *v = json_object_get(obj, key);
    if (!v) {
        if (required)
            return fail(c, 400, field, "%s is missing", key);
        *out = def;
        return true;
    }
    if (!json_is_integer(v))
        return fail(c, 400, field, "%s must be an integer", key);
    json_int_t x = json_integer_value(v);
    if (x < min || x > max)
        return fail(c, 400, field, "%s is %lld, must be %lld to %lld", key, (long long)x,
                    (long long)min, (long long)max);
    *out = x;
    return true;
}

/* An index into an array of n entries. */
bool get_index(struct ctx *c, json_t *obj, const char *key, const char *field, bool required,
                      size_t n, int64_t *out)
{
    json_t *v = json_object_get(obj, key);
    if (!v && !required) {
        *out = -1;
        return true;
    }
    if (!get_int(c, obj, key, field, required, 0, INT32_MAX, -1, out))
        return false;
    if ((uint64_t)*out >= n)
        return fail(c, 400, field, "%s %lld is out of range (%zu entries)", key, (long long)*out, n);
    return true;
}

double num_or(json_t *obj, const char *key, double def)
{
    /* Bounded so that every float the asset holds is finite. */
    json_t *v = json_object_get(obj, key);
    double x = json_is_number(v) ? json_number_value(v) : def;
    return isfinite(x) && fabs(x) <= 1e30 ? x : def;
}

/* n numbers at key into out (left as they are when absent). */
bool get_floats(struct ctx *c, json_t *obj, const char *key, const char *field, size_t n,
                       double *out)
{
    json_t *v = json_object_get(obj, key);
    if (!v)
        return true;
    if (!json_is_array(v) || json_array_size(v) != n)
        return fail(c, 400, field, "%s must be an array of %zu numbers", key, n);
    for (size_t i = 0; i < n; i++) {
        json_t *x = json_array_get(v, i);
        if (!json_is_number(x) || !(fabs(json_number_value(x)) <= 1e30))
            return fail(c, 400, field, "%s must be an array of %zu finite numbers", key, n);
        out[i] = json_number_value(x);
    }
    return true;
}

/* A name cut at ASSET_NAME_MAX - 1 bytes may end inside a UTF-8
 * sequence: drop the partial sequence, so that the name stays text. */
void utf8_trim(char *s)
{
    size_t n = strlen(s), i = n;
    while (i > 0 && ((unsigned char)s[i - 1] & 0xC0) == 0x80)
        i--;
    if (i > 0 && (unsigned char)s[i - 1] >= 0xC0) {
        unsigned char lead = (unsigned char)s[i - 1];
        size_t want = lead >= 0xF0 ? 4 : lead >= 0xE0 ? 3 : 2;
        if (n - (i - 1) < want)
            s[i - 1] = '\0';
    }
}

void copy_name(char *dst, json_t *obj, const char *fallback)
{
    const char *s = json_string_value(json_object_get(obj, "name"));
    snprintf(dst, ASSET_NAME_MAX, "%s", s && s[0] ? s : fallback);
    utf8_trim(dst);
}
