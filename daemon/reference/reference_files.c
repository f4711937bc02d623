#define _GNU_SOURCE
#include "daemon/reference/reference_files.h"

#include <limits.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

void reference_sampler_defaults(struct reference_sampler *s)
{
    *s = (struct reference_sampler){0};
}

void reference_sampler_resolve(const struct reference_sampler *given, bool uniform,
                               struct reference_sampler *out)
{
    const struct reference_sampler d =
        uniform ? (struct reference_sampler){.texture_size = 32, .ggx_samples = 16,
                                             .lambertian_samples = 16, .sheen_samples = 4,
                                             .lut_resolution = 128}
                : (struct reference_sampler){.texture_size = 128, .ggx_samples = 128,
                                             .lambertian_samples = 256, .sheen_samples = 16,
                                             .lut_resolution = 128};
    out->texture_size = given->texture_size ? given->texture_size : d.texture_size;
    out->ggx_samples = given->ggx_samples ? given->ggx_samples : d.ggx_samples;
    out->lambertian_samples = given->lambertian_samples ? given->lambertian_samples
                                                        : d.lambertian_samples;
    out->sheen_samples = given->sheen_samples ? given->sheen_samples : d.sheen_samples;
    out->lut_resolution = given->lut_resolution ? given->lut_resolution : d.lut_resolution;
}

static const struct {
    const char *key, *pattern; /* pattern: 1.1.0's line, %d its value */
    size_t offset;
    int lo, hi;
} SAMPLER[] = {
    {"texture_size", "this.textureSize = %d;", offsetof(struct reference_sampler, texture_size), 32, 1024},
    {"ggx_samples", "this.ggxSampleCount = %d;", offsetof(struct reference_sampler, ggx_samples), 16, 4096},
    {"lambertian_samples", "this.lambertianSampleCount = %d;", offsetof(struct reference_sampler, lambertian_samples), 16, 4096},
    {"sheen_samples", "this.sheenSamplCount = %d;", offsetof(struct reference_sampler, sheen_samples), 4, 1024},
    {"lut_resolution", "this.lutResolution = %d;", offsetof(struct reference_sampler, lut_resolution), 16, 1024},
};
/* 1.1.0's own values, in SAMPLER's order. */
static const int VIEWER_DEFAULTS[] = {256, 1024, 2048, 64, 1024};
enum { NSAMPLER = sizeof(SAMPLER) / sizeof(SAMPLER[0]) };

static int *field(struct reference_sampler *s, int i)
{
    return (int *)((char *)s + SAMPLER[i].offset);
}

void reference_sampler_from_json(const json_t *v, struct reference_sampler *s)
{
    reference_sampler_defaults(s);
    for (int i = 0; i < NSAMPLER; i++) {
        json_t *x = json_object_get(v, SAMPLER[i].key);
        if (json_is_integer(x))
            *field(s, i) = (int)json_integer_value(x);
    }
}

json_t *reference_sampler_to_json(const struct reference_sampler *s)
{
    json_t *o = json_object();
    for (int i = 0; o && i < NSAMPLER; i++)
        if (*field((struct reference_sampler *)s, i))
            json_object_set_new(o, SAMPLER[i].key,
                                json_integer(*field((struct reference_sampler *)s, i)));
    return o;
}

bool reference_sampler_parse(const json_t *v, struct reference_sampler *s, char *fieldname,
                             size_t field_cap, char *rule, size_t rule_cap)
{
    if (!json_is_object(v)) {
        snprintf(fieldname, field_cap, "fidelity.ibl_sampler");
        snprintf(rule, rule_cap, "must be an object of texture_size, ggx_samples, "
                 "lambertian_samples, sheen_samples, lut_resolution");
        return false;
    }
    const char *key;
    json_t *x;
    json_object_foreach((json_t *)v, key, x) {
        int i = 0;
        while (i < NSAMPLER && strcmp(key, SAMPLER[i].key) != 0)
            i++;
        snprintf(fieldname, field_cap, "fidelity.ibl_sampler.%s", key);
        if (i == NSAMPLER) {
            snprintf(rule, rule_cap, "unknown field (texture_size, ggx_samples, "
                     "lambertian_samples, sheen_samples, lut_resolution)");
            return false;
        }
        json_int_t n = json_is_integer(x) ? json_integer_value(x) : -1;
        bool pow2 = i != 0 && i != 4 ? true : (n > 0 && (n & (n - 1)) == 0);
        if (n < SAMPLER[i].lo || n > SAMPLER[i].hi || !pow2) {
            snprintf(rule, rule_cap, "must be an integer from %d to %d%s", SAMPLER[i].lo,
                     SAMPLER[i].hi, i == 0 || i == 4 ? ", a power of two" : "");
            return false;
        }
        *field(s, i) = (int)n;
    }
    return true;
}

char *reference_patch_viewer(const char *src, size_t len, const struct reference_sampler *s,
                             size_t *out_len, char *err, size_t errlen)
{
    char *out = malloc(len + 1);
    if (!out) {
        snprintf(err, errlen, "out of memory for the viewer's module");
        return NULL;
    }
    memcpy(out, src, len);
    out[len] = '\0';
    for (int i = 0; i < NSAMPLER; i++) {
        char from[96], to[96];
        snprintf(from, sizeof(from), SAMPLER[i].pattern, VIEWER_DEFAULTS[i]);
        snprintf(to, sizeof(to), SAMPLER[i].pattern, *field((struct reference_sampler *)s, i));
        char *at = strstr(out, from);
        if (!at || strstr(at + 1, from)) {
            snprintf(err, errlen, "the viewer's module is not %s %s's: \"%s\" is %s", 
                     REFERENCE_VIEWER_PACKAGE, REFERENCE_VIEWER_VERSION, from,
                     at ? "there twice" : "not there");
            free(out);
            return NULL;
        }
        /* Same length or shorter: pad with spaces so nothing moves. */
        size_t fl = strlen(from), tl = strlen(to);
        if (tl > fl) {
            snprintf(err, errlen, "%s: %d has more digits than the viewer's own value",
                     SAMPLER[i].key, *field((struct reference_sampler *)s, i));
            free(out);
            return NULL;
        }
        memcpy(at, to, tl);
        memset(at + tl, ' ', fl - tl);
    }
    *out_len = len;
    return out;
}

static bool file_there(const char *dir, const char *name)
{
    char p[2200];
    snprintf(p, sizeof(p), "%s/%s", dir, name);
    return access(p, R_OK) == 0;
}

/* The first of the candidates holding name; "" when none does. */
static void first_dir(char *out, size_t cap, const char *const *dirs, int n, const char *name)
{
    out[0] = '\0';
    for (int i = 0; i < n; i++)
        if (dirs[i] && dirs[i][0] && file_there(dirs[i], name)) {
            snprintf(out, cap, "%s", dirs[i]);
            return;
        }
}

static void find_on_path(char *out, size_t cap, const char *name)
{
    out[0] = '\0';
    const char *path = getenv("PATH");
    if (!path)
        path = "/usr/local/bin:/usr/bin:/bin";
    while (*path) {
        const char *colon = strchr(path, ':');
        size_t n = colon ? (size_t)(colon - path) : strlen(path);
        char p[1100];
        snprintf(p, sizeof(p), "%.*s/%s", (int)(n < 1000 ? n : 1000), path, name);
        if (n && access(p, X_OK) == 0) {
            snprintf(out, cap, "%.1000s", p);
            return;
        }
        path += n + (colon != NULL);
    }
}

void reference_paths_find(struct reference_paths *p, const char *chromium, const char *viewer_dir,
                          const char *page_dir, const char *program, const char *pkgdatadir)
{
    memset(p, 0, sizeof(*p));
    char self[PATH_MAX] = "";
    ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
    self[n > 0 ? n : 0] = '\0';
    char *slash = strrchr(self, '/');
    if (slash)
        *slash = '\0';
    char beside_viewer[PATH_MAX + 32], beside_page[PATH_MAX + 32], src_page[PATH_MAX + 64],
        share_viewer[1100], share_page[1100];
    snprintf(beside_viewer, sizeof(beside_viewer), "%s/reference-viewer", self);
    snprintf(beside_page, sizeof(beside_page), "%s/reference", self);
    /* A build tree: build/ holds no page; the source's daemon/reference does. */
    snprintf(src_page, sizeof(src_page), "%s/../daemon/reference", self);
    /* Installed: bindir/../share/shadebench, unless told otherwise. */
    if (pkgdatadir && pkgdatadir[0]) {
        snprintf(share_viewer, sizeof(share_viewer), "%s/reference-viewer", pkgdatadir);
        snprintf(share_page, sizeof(share_page), "%s/reference", pkgdatadir);
    } else {
        snprintf(share_viewer, sizeof(share_viewer), "%.900s/../share/shadebench/reference-viewer", self);
        snprintf(share_page, sizeof(share_page), "%.900s/../share/shadebench/reference", self);
    }

    if (chromium && chromium[0]) {
        if (access(chromium, X_OK) == 0)
            snprintf(p->chromium, sizeof(p->chromium), "%s", chromium);
    } else {
        find_on_path(p->chromium, sizeof(p->chromium), "chromium");
        if (!p->chromium[0])
            find_on_path(p->chromium, sizeof(p->chromium), "chromium-browser");
    }
    const char *vdirs[] = {viewer_dir, beside_viewer, share_viewer};
    first_dir(p->viewer_dir, sizeof(p->viewer_dir), viewer_dir && viewer_dir[0] ? vdirs : vdirs + 1,
              viewer_dir && viewer_dir[0] ? 1 : 2, REFERENCE_VIEWER_MODULE);
    const char *pdirs[] = {page_dir, beside_page, src_page, share_page};
    first_dir(p->page_dir, sizeof(p->page_dir), page_dir && page_dir[0] ? pdirs : pdirs + 1,
              page_dir && page_dir[0] ? 1 : 3, "page.js");
    if (program && program[0]) {
        if (access(program, X_OK) == 0)
            snprintf(p->program, sizeof(p->program), "%s", program);
    } else {
        char beside[PATH_MAX + 32];
        snprintf(beside, sizeof(beside), "%s/shadebench-reference", self);
        if (access(beside, X_OK) == 0)
            snprintf(p->program, sizeof(p->program), "%.1000s", beside);
    }
    if (!p->chromium[0])
        snprintf(p->missing, sizeof(p->missing), "Chromium: %s",
                 chromium && chromium[0] ? chromium
                                         : "neither chromium nor chromium-browser is on PATH");
    else if (!p->viewer_dir[0])
        snprintf(p->missing, sizeof(p->missing), "the Khronos glTF Sample Viewer (%s %s): no %s in %.150s%s%.150s (tools/setup vendors it)",
                 REFERENCE_VIEWER_PACKAGE, REFERENCE_VIEWER_VERSION, REFERENCE_VIEWER_MODULE,
                 viewer_dir && viewer_dir[0] ? viewer_dir : beside_viewer,
                 viewer_dir && viewer_dir[0] ? "" : " or ",
                 viewer_dir && viewer_dir[0] ? "" : share_viewer);
    else if (!p->page_dir[0])
        snprintf(p->missing, sizeof(p->missing), "the reference page: no page.js in %.300s",
                 page_dir && page_dir[0] ? page_dir : share_page);
    else if (!p->program[0])
        snprintf(p->missing, sizeof(p->missing), "shadebench-reference: not %s",
                 program && program[0] ? program : "beside the daemon");
}
