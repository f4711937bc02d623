#define _POSIX_C_SOURCE 200809L
#include "common/json_fields.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Length of the valid UTF-8 sequence at s (at most avail bytes), or 0 when
 * the bytes there are not one: a stray continuation byte, an overlong form,
 * a surrogate, a code point above U+10FFFF, or a sequence cut short. */
static size_t utf8_sequence(const unsigned char *s, size_t avail)
{
    unsigned char c = s[0];
    size_t len;
    unsigned cp;
    if (c < 0x80)
        return 1;
    if (c >= 0xc2 && c <= 0xdf)
        len = 2, cp = c & 0x1fu;
    else if (c >= 0xe0 && c <= 0xef)
        len = 3, cp = c & 0x0fu;
    else if (c >= 0xf0 && c <= 0xf4)
        len = 4, cp = c & 0x07u;
    else
        return 0;
    if (len > avail)
        return 0;
    for (size_t i = 1; i < len; i++) {
        if ((s[i] & 0xc0) != 0x80)
            return 0;
        cp = (cp << 6) | (s[i] & 0x3fu);
    }
    if ((len == 3 && cp < 0x800) || (len == 4 && (cp < 0x10000 || cp > 0x10ffff)) ||
        (cp >= 0xd800 && cp <= 0xdfff))
        return 0;
    return len;
}

size_t jf_utf8_prefix(const char *s, size_t max)
{
    size_t total = strlen(s), used = 0;
    while (used < total) {
        size_t len = utf8_sequence((const unsigned char *)s + used, total - used);
        if (len == 0)
            len = 1; /* a stray byte stands alone: cutting after it splits nothing */
        if (used + len > max)
            break;
        used += len;
    }
    return used;
}

void jf_utf8_sanitize(char *s, size_t cap)
{
    char out[1024];
    size_t in_len = strlen(s), o = 0, limit = (cap < sizeof(out) ? cap : sizeof(out)) - 1;
    /* A character cut short by an earlier truncation goes entirely. */
    size_t lead = in_len;
    while (lead > 0 && in_len - lead < 3 && ((unsigned char)s[lead - 1] & 0xc0) == 0x80)
        lead--;
    if (lead > 0 && (unsigned char)s[lead - 1] >= 0xc2 && (unsigned char)s[lead - 1] <= 0xf4) {
        unsigned char c = (unsigned char)s[lead - 1];
        size_t want = c >= 0xf0 ? 4 : (c >= 0xe0 ? 3 : 2);
        if (in_len - (lead - 1) < want)
            in_len = lead - 1;
    }
    for (size_t i = 0; i < in_len && o < limit;) {
        size_t len = utf8_sequence((const unsigned char *)s + i, in_len - i);
        if (len == 0) {
            /* Escaped, so the reader still sees which byte was there. */
            if (o + 4 > limit)
                break;
            snprintf(out + o, 5, "\\x%02x", (unsigned char)s[i]);
            o += 4;
            i++;
            continue;
        }
        if (o + len > limit)
            break;
        memcpy(out + o, s + i, len);
        o += len;
        i += len;
    }
    out[o] = '\0';
    memcpy(s, out, o + 1);
}

bool job_error_set(struct job_error *err, const char *field, const char *fmt, ...)
{
    snprintf(err->field, sizeof(err->field), "%s", field);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->message, sizeof(err->message), fmt, ap);
    va_end(ap);
    /* A cut may land inside a multi-byte character, and quoted input may hold
     * bytes that are not UTF-8 at all: JSON cannot carry either. */
    jf_utf8_sanitize(err->field, sizeof(err->field));
    jf_utf8_sanitize(err->message, sizeof(err->message));
    return false;
}

static size_t edit_distance(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    if (la > 40 || lb > 40)
        return 99;
    size_t row[41];
    for (size_t j = 0; j <= lb; j++)
        row[j] = j;
    for (size_t i = 1; i <= la; i++) {
        size_t diag = row[0];
        row[0] = i;
        for (size_t j = 1; j <= lb; j++) {
            size_t up = row[j];
            size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
            size_t best = diag + cost;
            if (row[j] + 1 < best)
                best = row[j] + 1;
            if (row[j - 1] + 1 < best)
                best = row[j - 1] + 1;
            row[j] = best;
            diag = up;
        }
    }
    return row[lb];
}

/* Rejects keys not in known, suggesting the closest one for typos. */
bool jf_check_keys(const json_t *obj, const char *prefix, const char *const *known,
                   struct job_error *err)
{
    const char *key;
    json_t *value;
    json_object_foreach((json_t *)obj, key, value) {
        bool found = false;
        const char *closest = NULL;
        size_t best = 3;
        for (const char *const *k = known; *k; k++) {
            if (strcmp(*k, key) == 0) {
                found = true;
                break;
            }
            size_t d = edit_distance(*k, key);
            if (d < best) {
                best = d;
                closest = *k;
            }
        }
        if (!found) {
            char field[64];
            /* An empty key still gets a name the reader can see. */
            const char *name = key[0] ? key : "\"\"";
            snprintf(field, sizeof(field), "%s%.*s", prefix, (int)jf_utf8_prefix(name, 40), name);
            if (closest)
                return job_error_set(err, field, "unknown field (did you mean '%s%s'?)",
                            prefix, closest);
            return job_error_set(err, field, "unknown field");
        }
    }
    return true;
}

bool jf_get_int(const json_t *obj, const char *key, const char *field,
                    long min, long max, int *out, struct job_error *err)
{
    json_t *v = json_object_get(obj, key);
    if (!v)
        return true;
    /* Accept 300.0 from tools that write every number as a double, but never 300.5. */
    double d;
    if (json_is_integer(v))
        d = (double)json_integer_value(v);
    else if (json_is_real(v) && floor(json_real_value(v)) == json_real_value(v))
        d = json_real_value(v);
    else
        return job_error_set(err, field, "must be an integer from %ld to %ld", min, max);
    if (d < (double)min || d > (double)max)
        return job_error_set(err, field, "must be an integer from %ld to %ld", min, max);
    *out = (int)d;
    return true;
}

bool jf_get_number(const json_t *obj, const char *key, const char *field,
                       double min, double max, double *out,
                       struct job_error *err)
{
    json_t *v = json_object_get(obj, key);
    if (!v)
        return true;
    if (!json_is_number(v) || !isfinite(json_number_value(v)) ||
        json_number_value(v) < min || json_number_value(v) > max)
        return job_error_set(err, field, "must be a number from %g to %g", min, max);
    *out = json_number_value(v);
    return true;
}

bool jf_get_bool(const json_t *obj, const char *key, const char *field,
                     bool *out, struct job_error *err)
{
    json_t *v = json_object_get(obj, key);
    if (!v)
        return true;
    if (!json_is_boolean(v))
        return job_error_set(err, field, "must be true or false");
    *out = json_is_true(v);
    return true;
}

bool jf_get_object(const json_t *obj, const char *key, const char *field,
                       json_t **out, struct job_error *err)
{
    *out = json_object_get(obj, key);
    if (*out && !json_is_object(*out))
        return job_error_set(err, field, "must be an object");
    return true;
}

bool jf_get_choice(const json_t *obj, const char *key, const char *field,
                   const char *const *choices, int *out, struct job_error *err)
{
    json_t *v = json_object_get(obj, key);
    if (!v)
        return true;
    for (int i = 0; json_is_string(v) && choices[i]; i++)
        if (strcmp(json_string_value(v), choices[i]) == 0) {
            *out = i;
            return true;
        }
    char list[256];
    jf_list_choices(choices, list, sizeof(list));
    return job_error_set(err, field, "must be one of: %s", list);
}

void jf_set_path(json_t *obj, const char *path, json_t *value)
{
    const char *dot;
    while ((dot = strchr(path, '.'))) {
        char head[64];
        snprintf(head, sizeof(head), "%.*s", (int)(dot - path), path);
        json_t *inner = json_object_get(obj, head);
        if (!json_is_object(inner)) {
            inner = json_object();
            json_object_set_new(obj, head, inner);
        }
        obj = inner;
        path = dot + 1;
    }
    json_object_set_new(obj, path, value);
}

void jf_list_choices(const char *const *choices, char *buf, size_t cap)
{
    size_t used = 0;
    buf[0] = '\0';
    for (int i = 0; choices[i] && used < cap; i++)
        used += (size_t)snprintf(buf + used, cap - used, "%s\"%s\"", i ? ", " : "", choices[i]);
}

json_t *job_error_to_json(const struct job_error *err)
{
    /* Callers may fill err by hand: sanitize a copy so that the answer is
     * always built. */
    struct job_error e = *err;
    e.field[sizeof(e.field) - 1] = '\0';
    e.message[sizeof(e.message) - 1] = '\0';
    jf_utf8_sanitize(e.field, sizeof(e.field));
    jf_utf8_sanitize(e.message, sizeof(e.message));
    return json_pack("{s:{s:s, s:s}}", "error", "field", e.field, "message", e.message);
}

/* The path of the value a scan is at, from its containers (keys and
 * indices), as the specs name fields: "scene.width", "vary.frames[1]". */
struct scan_frame {
    bool object;
    const char *key;
    size_t key_len, index;
};

static void scan_path(const struct scan_frame *st, int depth, char *out, size_t cap)
{
    size_t used = 0;
    out[0] = '\0';
    for (int d = 0; d < depth && used < cap; d++) {
        int n = st[d].object ? snprintf(out + used, cap - used, "%s%.*s", used ? "." : "",
                                        (int)st[d].key_len, st[d].key ? st[d].key : "")
                             : snprintf(out + used, cap - used, "[%zu]", st[d].index);
        used += n > 0 ? (size_t)n : 0;
    }
}

bool jf_check_numbers(const char *text, size_t len, struct job_error *err)
{
    enum { MAX_DEPTH = 32 };
    struct scan_frame st[MAX_DEPTH];
    int depth = 0, deep = 0; /* deep: levels past MAX_DEPTH, not tracked */
    bool expect_key = false;
    for (size_t i = 0; i < len; i++) {
        char ch = text[i];
        if (ch == '"') {
            size_t start = ++i;
            while (i < len && text[i] != '"')
                i += text[i] == '\\' ? 2 : 1;
            if (expect_key && depth && !deep && st[depth - 1].object) {
                st[depth - 1].key = text + start;
                st[depth - 1].key_len = (i < len ? i : len) - start;
                expect_key = false;
            }
            continue;
        }
        if (ch == '{' || ch == '[') {
            if (depth < MAX_DEPTH && !deep)
                st[depth++] = (struct scan_frame){.object = ch == '{'};
            else
                deep++;
            expect_key = ch == '{';
        } else if (ch == '}' || ch == ']') {
            if (deep)
                deep--;
            else if (depth)
                depth--;
        } else if (ch == ',') {
            if (depth && !deep && st[depth - 1].object)
                expect_key = true;
            else if (depth && !deep)
                st[depth - 1].index++;
        } else if (ch == '-' || (ch >= '0' && ch <= '9')) {
            /* A number: one whose digits are not all zero must not read as
             * 0 (strtod underflows 1e-400 to 0, which an integer field
             * would then take for 0). */
            size_t start = i;
            bool nonzero = false, exponent = false;
            while (i < len && text[i] && strchr("0123456789+-.eE", text[i])) {
                exponent |= text[i] == 'e' || text[i] == 'E';
                nonzero |= !exponent && text[i] >= '1' && text[i] <= '9';
                i++;
            }
            char num[400];
            size_t n = i - start;
            i--;
            if (!nonzero || n >= sizeof(num))
                continue;
            memcpy(num, text + start, n);
            num[n] = '\0';
            if (strtod(num, NULL) == 0.0) {
                char path[64];
                scan_path(st, depth, path, sizeof(path));
                return job_error_set(err, path[0] ? path : "body",
                                     "%s is too small for a double and would be read as 0; "
                                     "write 0, or a number from 1e-300", num);
            }
        }
    }
    return true;
}
