#ifndef SHADEBENCH_CULLING_INFO_H
#define SHADEBENCH_CULLING_INFO_H

/* The GL-free half shared by the many-lights techniques (the deferred ones
 * and those that cull lights into tiles or clusters): the choices of their
 * options, the g-buffer layout options every deferred technique carries, the cluster grid rule, and the light-bounds geometry (the screen
 * rectangle of a light sphere) that the CPU binning uses and
 * shaders/culling/light_bounds.glsl mirrors line for line. Any thread. */

#include <stdbool.h>
#include <stddef.h>

#include "common/json_fields.h"
#include "common/options.h"

/* G-buffer layouts. The lossy ones are there to show their loss. */
enum gbuffer_normal {
    GBUFFER_NORMAL_OCTAHEDRAL,       /* two channels, world space (default) */
    GBUFFER_NORMAL_FLOAT3,           /* three floats, world space */
    GBUFFER_NORMAL_XY_RECONSTRUCT_Z, /* view-space x, y; z rebuilt without its sign (seed 004) */
};
enum gbuffer_albedo {
    GBUFFER_ALBEDO_RGBA8,       /* 8 bits a channel (default) */
    GBUFFER_ALBEDO_PACK_SHIFT,  /* seed 001: bytes in one float by multiplied "shifts" (255 -> 254) */
    GBUFFER_ALBEDO_PACK_BASE10, /* seed 001's fix: decimal digits a channel in one float (100 levels) */
};
extern const char *const gbuffer_normal_choices[];
extern const char *const gbuffer_albedo_choices[];

struct gbuffer_options {
    int normal; /* enum gbuffer_normal */
    int albedo; /* enum gbuffer_albedo */
};

/* The two option rows of a technique whose options struct opts_type holds a
 * struct gbuffer_options named `member`. */
#define GBUFFER_OPTION_ROWS(opts_type, member)                                                    \
    {.name = "gbuffer.normal", .type = OPT_CHOICE, .def = GBUFFER_NORMAL_OCTAHEDRAL,             \
     .choices = gbuffer_normal_choices,                                                           \
     .summary = "normal layout: octahedral (two channels, default), float3, or "                  \
                "xy_reconstruct_z (seed 004: view-space x and y, z rebuilt without its sign)",    \
     .offset = offsetof(opts_type, member.normal)},                                               \
    {.name = "gbuffer.albedo", .type = OPT_CHOICE, .def = GBUFFER_ALBEDO_RGBA8,                  \
     .choices = gbuffer_albedo_choices,                                                           \
     .summary = "albedo layout: rgba8 (default), pack_shift (seed 001: the bytes in one float "   \
                "by multiplied shifts, a byte of 255 kept to 254) or pack_base10 (seed 001's "    \
                "decimal digits: two a channel, 100 levels, what fits a float)",                  \
     .offset = offsetof(opts_type, member.albedo)}

/* Bytes a pixel of a g-buffer (daemon/techniques/shared/gbuffer.c): albedo,
 * normal, material (and surface in textured scenes) a sample each, and with
 * MSAA the edge stencil; and of the light-count heat map a light-culling
 * technique publishes (one sample). For technique_info.planes_bpp. */
struct look_spec;
double gbuffer_planes_bpp(const struct gbuffer_options *opt, const struct look_spec *look,
                          bool textured, int samples);
#define HEAT_MAP_BPP 4.0

/* How the deferred technique bounds the pixels each light shades. */
enum light_bounds {
    LIGHT_BOUNDS_SCISSOR_TIGHT, /* the screen rectangle of the sphere's silhouette */
    LIGHT_BOUNDS_SCISSOR_LOOSE, /* the projected box of the sphere's world AABB corners */
    LIGHT_BOUNDS_VOLUME,        /* the sphere rasterised (back faces) */
    LIGHT_BOUNDS_FULLSCREEN,    /* every pixel */
};
extern const char *const light_bounds_choices[];

enum light_binning { LIGHT_BINNING_GPU, LIGHT_BINNING_CPU };
extern const char *const light_binning_choices[];

enum cluster_slices { CLUSTER_SLICES_LINEAR, CLUSTER_SLICES_EXPONENTIAL };
extern const char *const cluster_slices_choices[];

enum cluster_overflow { CLUSTER_OVERFLOW_FALLBACK, CLUSTER_OVERFLOW_FAIL };
extern const char *const cluster_overflow_choices[];

/* The options both clustered techniques share ("grid", "slices",
 * "max_lights_per_cluster", "overflow"). */
struct cluster_options {
    int grid[3];                /* tiles across, tiles down, depth slices */
    int slices;                 /* enum cluster_slices */
    int max_lights_per_cluster;
    int overflow;               /* enum cluster_overflow */
};
extern const int cluster_grid_default[3];

#define CLUSTER_OPTION_ROWS(opts_type, member)                                                    \
    {.name = "grid", .type = OPT_INT_LIST, .def_list = cluster_grid_default, .count = 3,         \
     .min = 1, .max = 1024,                                                                       \
     .summary = "froxel grid [x, y, z]: tiles across and down the screen, slices in depth "       \
                "(at most 1,048,576 clusters, and within the device's buffers)",                  \
     .offset = offsetof(opts_type, member.grid)},                                                 \
    {.name = "slices", .type = OPT_CHOICE, .def = CLUSTER_SLICES_EXPONENTIAL,                    \
     .choices = cluster_slices_choices,                                                           \
     .summary = "depth slices even in view depth (linear) or in its logarithm (exponential), "    \
                "between the nearest and farthest object",                                        \
     .offset = offsetof(opts_type, member.slices)},                                               \
    {.name = "max_lights_per_cluster", .type = OPT_INT, .def = 1024, .min = 1, .max = 65536,     \
     .summary = "lights a cluster's list keeps; more overflow (counted in the result)",           \
     .offset = offsetof(opts_type, member.max_lights_per_cluster)},                               \
    {.name = "overflow", .type = OPT_CHOICE, .def = CLUSTER_OVERFLOW_FALLBACK,                   \
     .choices = cluster_overflow_choices,                                                         \
     .summary = "an overflowing cluster shades with every light (fallback: correct, slower) "     \
                "or fails the job (fail)",                                                        \
     .offset = offsetof(opts_type, member.overflow)}

/* The most clusters a grid may have whatever the device: past it the light
 * grid alone takes more memory than any device here has to give. */
#define CLUSTER_GRID_MAX_CELLS (1 << 20)

/* Rejects a grid over CLUSTER_GRID_MAX_CELLS, naming "<prefix>.grid". */
bool cluster_grid_check(const int grid[3], const char *prefix, struct job_error *err);

/* The pixels a light sphere may touch: [x0, x1) x [y0, y1) in window
 * coordinates (origin bottom left), clamped to the w x h viewport.
 * LIGHT_BOUNDS_SCISSOR_TIGHT bounds the sphere's silhouette exactly
 * (tangent planes through the eye, Mara and McGuire 2013);
 * LIGHT_BOUNDS_SCISSOR_LOOSE bounds the projections of the 8 corners of its
 * world-space box. Both give the whole viewport when the sphere reaches the
 * near plane (conservative), and an empty rectangle when the sphere lies
 * outside the view. view, proj, view_proj: column-major. False when empty. */
bool light_rect(int kind, const float world_centre[3], float radius, const float view[16],
                const float proj[16], const float view_proj[16], float near_z, float far_z, int w,
                int h, int rect[4]);

#endif
