#ifndef SHADEBENCH_ASSET_CONVERT_H
#define SHADEBENCH_ASSET_CONVERT_H

/* The glTF 2.0 converter's core (shadebench-asset, never linked into the
 * daemon): checks a .glb or .gltf held in memory against the glTF rules
 * that keep an importer safe and against the limits, imports its meshes
 * with assimp, decodes its images (libpng, libjpeg) and fills a struct
 * asset (daemon/scene/asset.h). Single-threaded: one conversion per process
 * (assimp's importer state and libjpeg's error handling are not shared). */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/scene/asset.h"

/* Why a conversion failed: status 400 (the file is malformed), 422 (well
 * formed, but over a limit or using what the daemon does not take) or 500
 * (the converter itself: out of memory, an importer failure on a file the
 * checks passed); field names the thing ("accessors[3]", "images[2]",
 * "limits.max_texture_edge", "file"). */
struct asset_convert_error {
    int status;
    char field[128];
    char message[512];
};

/* Converts the glTF in data (GLB or JSON, told apart by content) into out
 * (zeroed first; finished on failure). */
bool asset_convert_buffer(const uint8_t *data, size_t len, const struct asset_limits *lim,
                          struct asset *out, struct asset_convert_error *err);

/* The same up to assimp's import, not included: the checks, then the
 * materials, the images (decoded) and the lights and cameras; no meshes.
 * The fuzz target's entry: assimp 5.2 crashes on some inputs the checks
 * pass (fuzzing finds one in seconds), which the converter, a child
 * process of the daemon, survives as a loader failure (422), and a fuzz
 * run that stopped on it would say nothing about the code of this
 * project. */
bool asset_convert_checks(const uint8_t *data, size_t len, const struct asset_limits *lim,
                          struct asset *out, struct asset_convert_error *err);

#endif
