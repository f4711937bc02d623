#ifndef SHADEBENCH_LOOK_LIGHTING_H
#define SHADEBENCH_LOOK_LIGHTING_H

/* The look's image-based lighting ("look.ibl") and shadows ("look.shadows"):
 * options, defaults, parsing with field-naming errors and the JSON written
 * back. The harness renders both for every technique (daemon/look/ibl.c,
 * shadows.c); the lighting library applies them in light_ambient and
 * light_contribution. GL-free; any thread. */

#include <jansson.h>
#include <stdbool.h>

#include "common/json_fields.h"

enum ibl_environment {
    IBL_ENV_SKY,     /* an analytic sky with a sun, made in code */
    IBL_ENV_UNIFORM, /* constant radiance (intensity): the white furnace's */
    IBL_ENV_ASSET,   /* an uploaded equirectangular HDR image: {"asset": NAME} */
};
extern const char *const ibl_environment_names[]; /* "sky", "uniform" (the strings) */

/* An environment asset's name: as scene.asset's (scene_spec.h:
 * SCENE_ASSET_NAME_MAX, scene_asset_name_valid). */
#define IBL_ENV_ASSET_NAME_MAX 128

#define IBL_MAX_PROBES 32
#define IBL_MAX_BLEND 8

struct ibl_probe_spec {
    double pos[3];
    double radius; /* the probe's influence: its weight reaches 0 here */
};

struct ibl_spec {
    bool enabled;
    int environment;  /* enum ibl_environment */
    /* IBL_ENV_ASSET: the stored asset's name, and its SHA-256 once the job
     * is accepted (the HTTP side looks it up, as for scene.asset), so that
     * the result names the exact file. */
    char env_asset[IBL_ENV_ASSET_NAME_MAX + 1];
    char env_sha256[65];
    double intensity; /* scales the environment's radiance */
    int probes;       /* light probes capturing the scene; 0: the environment alone */
    bool placed;      /* probes given as a list (probe[]), else placed over the objects */
    struct ibl_probe_spec probe[IBL_MAX_PROBES];
    int resolution;   /* capture cube face edge (the prefiltered map's level 0) */
    int blend;        /* probes blended per pixel, the most important first */
    int samples;      /* GGX samples per prefiltered texel */
};

enum shadow_overflow { SHADOW_OVERFLOW_DROP_REPORT, SHADOW_OVERFLOW_FAIL };
enum shadow_layout {
    SHADOW_LAYOUT_ATLAS, /* every light's six faces in one 2D atlas, sized by importance */
    SHADOW_LAYOUT_CUBES, /* one cube map per light (a cube map array), all tile x tile */
};
extern const char *const shadow_overflow_names[];
extern const char *const shadow_layout_names[];

#define SHADOW_MIN_TILE 4
#define SHADOW_MAX_ATLAS 16384

struct shadow_spec {
    bool enabled;
    int layout;          /* enum shadow_layout */
    int atlas;           /* atlas edge in texels: the memory bound of either layout */
    int tile;            /* face edge for every light; 0: "auto", by importance on screen */
    int min_tile, max_tile; /* auto's bounds */
    int pcf;             /* filter radius in texels: (2 pcf + 1)^2 bilinear compares */
    double bias;         /* depth bias along the light ray, world units */
    double normal_offset; /* receiver moved along its normal, in shadow-map texels */
    int overflow;        /* enum shadow_overflow */
};

void ibl_spec_defaults(struct ibl_spec *s);
void shadow_spec_defaults(struct shadow_spec *s);

/* v: true, false, null or an object of options (which switches it on);
 * field is "look.ibl" / "look.shadows", the prefix of every error. */
bool ibl_spec_parse(const json_t *v, const char *field, struct ibl_spec *s, struct job_error *err);
bool shadow_spec_parse(const json_t *v, const char *field, struct shadow_spec *s,
                       struct job_error *err);

/* false when off, else every option. New reference. */
json_t *ibl_spec_to_json(const struct ibl_spec *s);
json_t *shadow_spec_to_json(const struct shadow_spec *s);

#endif
