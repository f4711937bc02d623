#ifndef SHADEBENCH_EFFECT_INFO_H
#define SHADEBENCH_EFFECT_INFO_H

/* The GL-free half of the post effects the harness runs after any technique
 * on its HDR output (look.post): each effect's name, summary, the named
 * passes it runs and its options, declared as a table of the same
 * struct technique_option the techniques use and read by the same generic
 * parser (technique_options_parse), so bad input is answered alike:
 * "look.post[1].radius: must be an integer from 2 to 32".
 *
 * The registry (effect_infos) is a static array: effects are part of the
 * harness, not of the technique catalogue a caller hands in. The GL half
 * (daemon/effects/effect.h) points at these infos. Immutable; any thread. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "common/json_fields.h"
#include "daemon/techniques/technique_info.h"

/* Effects the registry may hold (at most TECHNIQUE_MAX, as /v1/info lists
 * them through a technique catalogue). */
#define EFFECT_REGISTRY_MAX 16
/* Effects one look may chain. */
#define POST_MAX_EFFECTS 8
/* Named passes one effect instance may run in a frame. */
#define EFFECT_MAX_PASSES 6
/* Timed passes a chain may add: the timer's 32 sections hold a technique's
 * 16, the chain's and the harness's resolve. */
#define POST_MAX_PASSES 15
/* Room for a pass name with its instance label: "bloom2.composite". */
#define POST_PASS_NAME_BYTES 40

struct effect_info {
    const char *name;
    const char *summary;
    /* Every pass the effect may run, NULL-terminated (for /v1/info). */
    const char *const *passes;
    /* Terminated by an entry with name NULL. */
    const struct technique_option *options;
    size_t options_size; /* <= TECHNIQUE_OPTIONS_BYTES */
    /* Rules across options after every field parsed; names the option
     * relative to the effect ("downsample"), the caller prefixes the path.
     * May be NULL. */
    bool (*check)(const void *opts, struct job_error *err);
    /* The passes one instance runs with these options, in frame order, as
     * suffixes ("bright", "blur_h", ...); returns how many (at most
     * EFFECT_MAX_PASSES). */
    int (*active_passes)(const void *opts, const char **out);
};

/* bloom: bright pass, Gaussian blur of what passed it, added back. */
enum bloom_kernel { BLOOM_SEPARABLE, BLOOM_2D };
struct bloom_options {
    double threshold; /* luminance above which light blooms */
    int kernel;       /* enum bloom_kernel */
    int radius;       /* taps each side: (2r+1) a row, (2r+1)^2 for 2d */
    double intensity; /* scale of the blurred light added back */
    int downsample;   /* 0: blur at full size; n: a mip chain of n halvings */
};

/* toon: colour ramp and outlines. */
enum toon_edges { TOON_EDGES_SOBEL, TOON_EDGES_DEPTH_DIFF, TOON_EDGES_NONE };
struct toon_options {
    int levels;              /* steps of the luminance ramp */
    int edges;               /* enum toon_edges */
    double threshold;        /* relative view-depth difference that makes an edge */
    double normal_threshold; /* sobel: normal gradient that makes an edge */
    int thickness;           /* pixels between the samples the edge test compares */
};

/* ssao: hemisphere ambient occlusion, blurred, multiplied into the colour. */
struct ssao_options {
    int samples;      /* hemisphere samples per pixel */
    double radius;    /* world units */
    double bias;      /* depth bias against self-occlusion, world units */
    bool blur;        /* 4x4 blur over the noise tile (seed 002's "blurry SSAO") */
    double intensity; /* exponent on the occlusion term: 0 none, 1 as computed */
};

extern const struct effect_info bloom_info, toon_info, ssao_info;

/* The registry, NULL-terminated, in /v1/info order. */
extern const struct effect_info *const effect_infos[];

/* Index of name in effect_infos, or -1. */
int effect_find(const char *name);

/* One effect of a chain and its options (the effect's struct, by bytes). */
struct post_effect {
    int effect; /* index into effect_infos */
    struct technique_options options;
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

/* /v1/info's "effects": each effect with its passes and options (type,
 * default, rule, summary), as techniques are described. New reference. */
json_t *effect_catalog_json(void);

#endif
