/* TEMPORARY: replaced by asset.c at merge.
 *
 * The cache reader and writer (daemon/scene/asset.c) are being written on
 * the converter's branch; these definitions of asset.h's functions let the
 * renderer's branch link and run meanwhile. Every reading or writing
 * function fails with "asset cache reader not built", so a job naming
 * scene.asset fails cleanly in run_prepare; the textured preset builds its
 * asset in memory (asset_synthetic.c) and needs none of them. Delete this
 * file (and its line in Makefile.am) when asset.c arrives. GL-free; any
 * thread. */
#include "daemon/scene/asset.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const asset_texture_slot_names[] = {"base_color", "metallic_roughness", "normal",
                                                "occlusion", "emissive", NULL};
const char *const asset_alpha_mode_names[] = {"opaque", "mask", "blend", NULL};
const char *const asset_light_type_names[] = {"point", "spot", "directional", NULL};

static const char NOT_BUILT[] = "asset cache reader not built";

void asset_limits_defaults(struct asset_limits *lim)
{
    memset(lim, 0, sizeof(*lim));
    lim->max_file_bytes = 256ull << 20;
    lim->max_vertices = 16u << 20;
    lim->max_indices = 48u << 20;
    lim->max_texture_pixels = 256ull << 20;
    lim->max_texture_edge = 8192;
    lim->max_meshes = 65536;
    lim->max_materials = lim->max_images = 4096;
    lim->max_lights = lim->max_cameras = 1024;
}

json_t *asset_limits_to_json(const struct asset_limits *lim)
{
    (void)lim;
    return json_object();
}

bool asset_file_write(const struct asset *a, const char *path, char *err, size_t errlen)
{
    (void)a, (void)path;
    snprintf(err, errlen, "%s", NOT_BUILT);
    return false;
}

bool asset_file_read(struct asset *out, const char *path, const struct asset_limits *lim,
                     char *err, size_t errlen)
{
    (void)lim;
    memset(out, 0, sizeof(*out));
    snprintf(err, errlen, "%s: %s", path, NOT_BUILT);
    return false;
}

bool asset_file_parse(struct asset *out, const void *data, size_t len,
                      const struct asset_limits *lim, char *err, size_t errlen)
{
    (void)data, (void)len, (void)lim;
    memset(out, 0, sizeof(*out));
    snprintf(err, errlen, "%s", NOT_BUILT);
    return false;
}

void asset_finish(struct asset *a)
{
    if (a)
        memset(a, 0, sizeof(*a));
}

json_t *asset_describe(const struct asset *a)
{
    (void)a;
    return NULL;
}
