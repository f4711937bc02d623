#ifndef SHADEBENCH_ASSET_STORE_H
#define SHADEBENCH_ASSET_STORE_H

/* Where an asset's files live in the state directory, and the limits the
 * converter is run with. An asset is named by the SHA-256 of the file that
 * was uploaded (or found in --asset-dir):
 *
 *   STATE_DIR/assets/SHA256.sbasset   the converter's cache (asset.h), what
 *                                     the render thread reads
 *   STATE_DIR/assets/SHA256.glb       the uploaded file as sent (or .gltf, or
 *                                     .hdr for an environment map)
 *
 * Several names may point at one hash; the files go when none does. A job's
 * spec carries scene.asset_sha256 (filled when it is accepted), so the
 * render thread needs no store: asset_store_cache_path(state_dir,
 * spec->scene.asset_sha256, ...) and asset_file_read.
 *
 * GL-free, no state: any thread (the render thread included). */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <jansson.h>

#include "daemon/scene/asset.h"

#define ASSET_STORE_DIR "assets"
#define ASSET_CACHE_EXT "sbasset"

/* True when sha256 is 64 lowercase hexadecimal digits. */
bool asset_store_sha256_valid(const char *sha256);

/* STATE_DIR/assets/SHA256.sbasset into out; false (out "") when it does not
 * fit or the hash is not 64 lowercase hex digits (so that no spec can make
 * the render thread open another path). */
bool asset_store_cache_path(const char *state_dir, const char *sha256, char *out, size_t cap);
/* STATE_DIR/assets/SHA256.EXT, ext "glb", "gltf", "hdr" or "exr" (an
 * environment map: its cache file holds the decoded image,
 * daemon/scene/environment.h; an OpenEXR one's SHA256.hdr is its Radiance
 * copy for the Khronos viewer, which reads only .hdr). */
bool asset_store_original_path(const char *state_dir, const char *sha256, const char *ext,
                               char *out, size_t cap);
/* STATE_DIR/assets. */
bool asset_store_dir(const char *state_dir, char *out, size_t cap);


/* What a conversion may take beside the asset's own limits. */
struct asset_run_limits {
    uint64_t memory_bytes; /* the converter's address space (RLIMIT_AS, --max-memory) */
    unsigned cpu_s;        /* its CPU seconds (RLIMIT_CPU, --max-cpu-seconds) */
    double wall_s;         /* then it is killed */
};
void asset_run_limits_defaults(struct asset_run_limits *r);

#endif
