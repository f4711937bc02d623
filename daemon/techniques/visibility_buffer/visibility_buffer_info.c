#include "daemon/techniques/visibility_buffer/visibility_buffer_info.h"

#include <stddef.h>

static const char *const passes[] = {"binning", "visibility", "classify", "shading", NULL};
static const char *const lights_choices[] = {"all", "clustered", NULL};
static const char *const ids_choices[] = {"auto", "wide", NULL};

static const struct opt_field options[] = {
    /* clustered by default: on llvmpipe it costs less than every light at
     * every count measured on the presets (4 to 1024 lights; at 256 on the
     * lights preset at 1080x720, 236 against 3,840 ms a frame), and it is
     * how engines that ship a visibility buffer light it. */
    {.name = "lights", .type = OPT_CHOICE, .def = VIS_LIGHTS_CLUSTERED, .choices = lights_choices,
     .summary = "lights each pixel loops over: clustered (the froxel grid of the clustered "
                "techniques, built in the binning pass; grid, slices, max_lights_per_cluster "
                "and overflow apply), or all (as forward)",
     .offset = offsetof(struct visibility_buffer_options, lights)},
    {.name = "ids", .type = OPT_CHOICE, .def = VIS_IDS_AUTO, .choices = ids_choices,
     .summary = "a pixel's instance and triangle ids: auto (32 bits, R32UI, when the instances "
                "and the largest mesh's triangles fit; else 64) or wide (64 bits, RG32UI)",
     .offset = offsetof(struct visibility_buffer_options, ids)},
    CLUSTER_OPTION_ROWS(struct visibility_buffer_options, cluster),
    {0},
};

static bool check(void *opts, const char *prefix, struct job_error *err)
{
    const struct visibility_buffer_options *o = opts;
    return cluster_grid_check(o->cluster.grid, prefix, err);
}

/* What job_cost charges: the ids (64 bits a sample at most, RG32UI: whether
 * 32 fit is known only with the scene) and the key target (depth and
 * stencil, 8 bytes a sample), every sample counted. */
static double planes_bpp(const void *options, const struct look_spec *look, bool textured,
                         int samples)
{
    (void)options, (void)look, (void)textured;
    return (8.0 + 8.0) * (samples > 0 ? samples : 1);
}

const struct technique_info visibility_buffer_info = {
    .name = "visibility_buffer",
    .summary = "visibility buffer (Burns and Hunt 2013): instance and triangle ids and depth "
               "per pixel, then one shading pass that fetches the triangle's vertices, "
               "rebuilds its attributes and their derivatives and shades every pixel once "
               "(per material in asset scenes); lights all or clustered",
    .passes = passes,
    .options = {.fields = options,
                .size = sizeof(struct visibility_buffer_options),
                .check = check},
    .flags = TECHNIQUE_BOUNDED_LIGHT_LISTS,
    .planes_bpp = planes_bpp,
};

int vis_triangle_bits(long long instances, long long max_triangles)
{
    int tri = 0;
    while (tri < 32 && (1LL << tri) < max_triangles)
        tri++;
    int inst = 0;
    while (inst < 33 && (1LL << inst) < instances + 1)
        inst++;
    return tri + inst <= 32 ? tri : -1;
}

uint32_t vis_pack(int instance, uint32_t triangle, int triangle_bits)
{
    return ((uint32_t)(instance + 1) << triangle_bits) | triangle;
}

bool vis_unpack(uint32_t id, int triangle_bits, int *instance, uint32_t *triangle)
{
    if (!id)
        return false;
    uint32_t mask = triangle_bits >= 32 ? 0xffffffffu : (1u << triangle_bits) - 1u;
    *instance = (int)(triangle_bits >= 32 ? 0 : (id >> triangle_bits)) - 1;
    *triangle = id & mask;
    return true;
}
