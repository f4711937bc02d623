#ifndef SHADEBENCH_REFERENCE_FILES_H
#define SHADEBENCH_REFERENCE_FILES_H

/* What the Khronos reference needs on disk, shared by the daemon (which says
 * whether the reference is available: /v1/info) and by its child,
 * shadebench-reference: the vendored viewer (tools/setup unpacks
 * @khronosgroup/gltf-viewer into build/reference-viewer; make install puts
 * it in $(pkgdatadir)/reference-viewer), the page (page.html, page.js,
 * beside it in $(pkgdatadir)/reference, or daemon/reference in a build
 * tree) and Chromium. And the one change made to the viewer as served: its
 * IBL sampler's sizes, which at 1.1.0's values (256-texel cube faces, 1024
 * GGX and 2048 Lambertian samples a texel, a 1024x1024 BRDF table) take
 * over 8 minutes in SwiftShader on 2 cores. GL-free; any thread. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#define REFERENCE_VIEWER_PACKAGE "@khronosgroup/gltf-viewer"
#define REFERENCE_VIEWER_VERSION "1.1.0"
#define REFERENCE_VIEWER_MODULE "gltf-viewer.module.js"
/* The largest file the page is served (the asset is the largest: the
 * daemon's upload limit is 256 MiB by default). */
#define REFERENCE_MAX_SERVED_BYTES (512ull << 20)

/* The viewer's iblSampler: cube face edge, GGX, Lambertian and Charlie
 * (sheen) samples a texel, the BRDF table's edge. */
struct reference_sampler {
    int texture_size, ggx_samples, lambertian_samples, sheen_samples, lut_resolution;
};
/* A job's sampler: 0 in a field, the environment's default
 * (reference_sampler_resolve). */
void reference_sampler_defaults(struct reference_sampler *s);
/* The sizes the viewer runs with: the given fields, the rest by the
 * environment. A uniform environment filters to itself at any size, so it
 * takes the least that works (32-texel faces: two mip levels, the fewest
 * the viewer's roughness = level / (levels - 1) takes; 16 samples; the
 * BRDF table, which does depend on its size, 128 a side); an image takes
 * 128-texel faces, 128 GGX, 256 Lambertian and 16 Charlie samples a texel
 * and a 128-texel table (docs/assets.md, "How the two filter
 * environments"). */
void reference_sampler_resolve(const struct reference_sampler *given, bool uniform,
                               struct reference_sampler *out);
/* Reads the fields present over the defaults (no checks: the daemon checked). */
void reference_sampler_from_json(const json_t *v, struct reference_sampler *s);
json_t *reference_sampler_to_json(const struct reference_sampler *s);
/* Checks a job's fidelity.ibl_sampler object; false with field and rule. */
bool reference_sampler_parse(const json_t *v, struct reference_sampler *s, char *field,
                             size_t field_cap, char *rule, size_t rule_cap);

/* The viewer's module text with the sampler's five settings replaced; NULL
 * with err when one of them is not found as 1.1.0 writes it (another
 * version: the reference would be silently slow or different). malloc'ed. */
char *reference_patch_viewer(const char *src, size_t len, const struct reference_sampler *s,
                             size_t *out_len, char *err, size_t errlen);

/* Where the reference's parts are, and whether they are there. */
struct reference_paths {
    char chromium[1024];   /* an executable, or "" */
    char viewer_dir[1024]; /* holds REFERENCE_VIEWER_MODULE and libs/, or "" */
    char page_dir[1024];   /* holds page.html and page.js, or "" */
    char program[1024];    /* shadebench-reference, or "" */
    char missing[512];     /* "" when everything is there, else what is not and where it looked */
};

/* chromium, viewer_dir, page_dir, program: the operator's paths (NULL or
 * "": look in the usual places: chromium or chromium-browser on PATH; the
 * viewer and the page beside the daemon's executable (a build tree) or in
 * pkgdatadir; shadebench-reference beside the daemon). */
void reference_paths_find(struct reference_paths *p, const char *chromium, const char *viewer_dir,
                          const char *page_dir, const char *program, const char *pkgdatadir);

#endif
