/* A technique catalogue for the GL-free unit tests: forward and unlit as the
 * registry declares them (no options), OSL's real options, and "demo", a
 * technique with one option of every kind, for the generic option parser. */
#ifndef SHADEBENCH_CATALOG_FIXTURE_H
#define SHADEBENCH_CATALOG_FIXTURE_H

#include <stddef.h>

#include "daemon/techniques/osl/osl_info.h"
#include "daemon/techniques/technique_info.h"

struct demo_options {
    int tile;
    double radius;
    bool fallback;
    int normal;
    int albedo;
    int size;
    int grid[3];
};

static const char *const fixture_passes[] = {"shading", NULL};
static const char *const fixture_normals[] = {"octahedral", "float3", "xy_reconstruct_z", NULL};
static const char *const fixture_albedos[] = {"rgba8", "pack_shift", NULL};
static const int fixture_grid[3] = {16, 9, 24};

static const struct technique_option fixture_demo_options[] = {
    {.name = "tile", .type = TOPT_INT, .def = 16, .min = 8, .max = 128,
     .offset = offsetof(struct demo_options, tile)},
    {.name = "radius", .type = TOPT_NUMBER, .def = 0.5, .min = 0, .max = 2,
     .offset = offsetof(struct demo_options, radius)},
    {.name = "fallback", .type = TOPT_BOOL, .def = 1,
     .offset = offsetof(struct demo_options, fallback)},
    {.name = "gbuffer.normal", .type = TOPT_CHOICE, .choices = fixture_normals,
     .offset = offsetof(struct demo_options, normal)},
    {.name = "gbuffer.albedo", .type = TOPT_CHOICE, .choices = fixture_albedos, .def = 1,
     .offset = offsetof(struct demo_options, albedo)},
    {.name = "size", .type = TOPT_POW2_OR_AUTO, .def = 0, .min = 8, .max = 1024,
     .offset = offsetof(struct demo_options, size)},
    {.name = "grid", .type = TOPT_INT_LIST, .count = 3, .def_list = fixture_grid, .min = 1,
     .max = 64, .offset = offsetof(struct demo_options, grid)},
    {0},
};

static const struct technique_info fixture_forward = {
    .name = "forward", .summary = "forward", .passes = fixture_passes};
static const struct technique_info fixture_unlit = {
    .name = "unlit", .summary = "unlit", .passes = fixture_passes};
static const struct technique_info fixture_demo = {
    .name = "demo", .summary = "every option kind", .passes = fixture_passes,
    .options = fixture_demo_options, .options_size = sizeof(struct demo_options)};

static inline const struct technique_catalog *fixture_catalog(void)
{
    static struct technique_catalog c;
    if (!c.count) {
        technique_catalog_add(&c, &fixture_forward);
        technique_catalog_add(&c, &fixture_unlit);
        technique_catalog_add(&c, &osl_info);
        technique_catalog_add(&c, &fixture_demo);
    }
    return &c;
}

#endif
