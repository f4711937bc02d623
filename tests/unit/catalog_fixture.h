/* The technique catalogue for the GL-free unit tests: every registered
 * technique as the daemon catalogues it (technique_catalog_init, no GL),
 * and "demo", a technique with one option of every kind, for the generic
 * option reader. */
#ifndef SHADEBENCH_CATALOG_FIXTURE_H
#define SHADEBENCH_CATALOG_FIXTURE_H

#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

#include "daemon/techniques/catalog.h"
#include "daemon/techniques/osl/osl_info.h"

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

static const struct opt_field fixture_demo_options[] = {
    {.name = "tile", .type = OPT_INT, .def = 16, .min = 8, .max = 128,
     .offset = offsetof(struct demo_options, tile)},
    {.name = "radius", .type = OPT_NUMBER, .def = 0.5, .min = 0, .max = 2,
     .offset = offsetof(struct demo_options, radius)},
    {.name = "fallback", .type = OPT_BOOL, .def = 1,
     .offset = offsetof(struct demo_options, fallback)},
    {.name = "gbuffer.normal", .type = OPT_CHOICE, .choices = fixture_normals,
     .offset = offsetof(struct demo_options, normal)},
    {.name = "gbuffer.albedo", .type = OPT_CHOICE, .choices = fixture_albedos, .def = 1,
     .offset = offsetof(struct demo_options, albedo)},
    {.name = "size", .type = OPT_POW2_OR_AUTO, .def = 0, .min = 8, .max = 1024,
     .offset = offsetof(struct demo_options, size)},
    {.name = "grid", .type = OPT_INT_LIST, .count = 3, .def_list = fixture_grid, .min = 1,
     .max = 64, .offset = offsetof(struct demo_options, grid)},
    {0},
};

static const struct technique_info fixture_demo = {
    .name = "demo", .summary = "every option kind", .passes = fixture_passes,
    .options = {.fields = fixture_demo_options, .size = sizeof(struct demo_options)}};

static inline const struct technique_catalog *fixture_catalog(void)
{
    static struct technique_catalog c;
    if (!c.count) {
        char err[256];
        if (!technique_catalog_init(&c, err, sizeof(err)) ||
            !technique_catalog_add(&c, &fixture_demo, err, sizeof(err))) {
            fprintf(stderr, "catalog fixture: %s\n", err);
            abort();
        }
    }
    return &c;
}

#endif
