#define _POSIX_C_SOURCE 200809L
#include "daemon/store/asset_store.h"

#include <stdio.h>
#include <string.h>

bool asset_store_sha256_valid(const char *sha256)
{
    if (!sha256 || strlen(sha256) != 64)
        return false;
    for (const char *p = sha256; *p; p++)
        if (!((*p >= '0' && *p <= '9') || (*p >= 'a' && *p <= 'f')))
            return false;
    return true;
}

static bool fits(int n, size_t cap, char *out)
{
    if (n < 0 || (size_t)n >= cap) {
        if (cap)
            out[0] = '\0';
        return false;
    }
    return true;
}

bool asset_store_dir(const char *state_dir, char *out, size_t cap)
{
    return fits(snprintf(out, cap, "%s/%s", state_dir, ASSET_STORE_DIR), cap, out);
}

bool asset_store_cache_path(const char *state_dir, const char *sha256, char *out, size_t cap)
{
    if (!asset_store_sha256_valid(sha256)) {
        if (cap)
            out[0] = '\0';
        return false;
    }
    return fits(snprintf(out, cap, "%s/%s/%s.%s", state_dir, ASSET_STORE_DIR, sha256,
                         ASSET_CACHE_EXT), cap, out);
}

bool asset_store_original_path(const char *state_dir, const char *sha256, const char *ext,
                               char *out, size_t cap)
{
    if (!asset_store_sha256_valid(sha256) ||
        (strcmp(ext, "glb") != 0 && strcmp(ext, "gltf") != 0 && strcmp(ext, "hdr") != 0 &&
         strcmp(ext, "exr") != 0)) {
        if (cap)
            out[0] = '\0';
        return false;
    }
    return fits(snprintf(out, cap, "%s/%s/%s.%s", state_dir, ASSET_STORE_DIR, sha256, ext), cap,
                out);
}

/* AddressSanitizer builds: GCC says so with __SANITIZE_ADDRESS__, clang
 * with __has_feature. */
#if defined(__SANITIZE_ADDRESS__)
#define SB_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SB_ASAN 1
#endif
#endif

void asset_run_limits_defaults(struct asset_run_limits *r)
{
    /* Decoded textures alone may reach 1 GiB at the default limits; the
     * importer's own copies come on top. */
    r->memory_bytes = 4ull << 30;
#if defined(SB_ASAN)
    /* AddressSanitizer reserves terabytes of shadow address space at start:
     * under an address-space cap the instrumented converter cannot start.
     * Sanitizer builds run it uncapped (CPU time and the wall-clock
     * time-out still apply). */
    r->memory_bytes = 0;
#endif
    r->cpu_s = 120;
    r->wall_s = 180;
}
