/* PATH_MAX (limits.h) under -std=c11, as the assets' other files. */
#define _GNU_SOURCE
/* The assets: pins (assets.h). A job or sweep naming an asset is pinned to
 * the asset's hash in the step that resolves the name, under the assets'
 * lock, so that a DELETE or a replacing PUT can never come between the two:
 * a name with a pin cannot be deleted (409), and a pinned hash keeps its
 * files whatever replaces its name. A submission's pin lasts until its job
 * is live (the queued or running job protects the hash from then on:
 * queue_asset_in_use) or refused; a sweep's lasts as long as the sweep. A
 * hash no name points at goes as soon as its last pin and its last job
 * have let go of it. */
#include "daemon/jobs/assets_impl.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "common/log.h"

struct asset_pin *asset_pin_find_locked(struct assets *a, const char *name, const char *sha)
{
    for (size_t i = 0; i < a->npins; i++)
        if ((!name || strcmp(a->pins[i].name, name) == 0) &&
            (!sha || strcmp(a->pins[i].sha256, sha) == 0))
            return &a->pins[i];
    return NULL;
}

static bool pin_add_locked(struct assets *a, const char *name, const char *sha)
{
    struct asset_pin *p = asset_pin_find_locked(a, name, sha);
    if (p) {
        p->count++;
        return true;
    }
    if (a->npins == a->pins_cap) {
        size_t cap = a->pins_cap ? a->pins_cap * 2 : 16;
        struct asset_pin *grown = realloc(a->pins, cap * sizeof(*grown));
        if (!grown)
            return false;
        a->pins = grown;
        a->pins_cap = cap;
    }
    p = &a->pins[a->npins++];
    snprintf(p->name, sizeof(p->name), "%s", name);
    snprintf(p->sha256, sizeof(p->sha256), "%s", sha);
    p->count = 1;
    return true;
}

/* What a job on the hash holds in memory while it renders, at most (an
 * upper bound, as job_cost.h asks): the cache file read in whole
 * (asset_file_read), its geometry again on the GPU, and each image up to
 * twice there (sRGB and linear) with its mipmaps (4/3). On llvmpipe the
 * GPU's copies live in the daemon's memory too. 0 when the files cannot be
 * read (the job then fails at its start, naming the cache). */
static double memory_bytes(const struct assets *a, const char *sha)
{
    char path[PATH_MAX + 80];
    asset_path(a, sha, ASSET_CACHE_EXT, path, sizeof(path));
    struct stat st;
    if (stat(path, &st) != 0)
        return 0;
    asset_path(a, sha, "json", path, sizeof(path));
    json_t *d = json_load_file(path, 0, NULL);
    double cache = (double)st.st_size;
    double textures = 4.0 * (double)json_integer_value(json_object_get(d, "texture_pixels"));
    json_decref(d);
    if (textures > cache)
        textures = cache;
    return cache + (cache - textures) + textures * 2.0 * 4.0 / 3.0;
}

/* One name pinned to its hash, under the lock: the name's current hash
 * (into sha when empty, else checked against it), of the kind asked for (an
 * environment map or a glTF scene). field and sha_field name what the job
 * called it. */
static bool pin_name_locked(struct assets *a, const char *name, char sha[65], bool environment,
                            bool restore, const char *field, const char *sha_field,
                            struct assets_error *e)
{
    struct store_asset r;
    memset(&r, 0, sizeof(r));
    bool ok = false;
    if (asset_dir_not_ready_locked(a, name, field, e))
        goto out;
    enum store_found f = store_asset_get(a->store, name, &r);
    if (f == STORE_ERROR) {
        asset_refuse(e, ASSETS_INTERNAL, field, "cannot read the asset records (see the log)");
        goto out;
    }
    const char *want = sha;
    bool current = f == STORE_FOUND && (!want[0] || strcmp(want, r.sha256) == 0);
    /* A hash the name no longer points at: still there while a sweep (or a
     * submission) holds it under that name, or, for a sweep resumed at
     * start-up, while its files are. */
    char cache[PATH_MAX + 80];
    if (want[0])
        asset_path(a, want, ASSET_CACHE_EXT, cache, sizeof(cache));
    bool held = !current && want[0] &&
                (asset_pin_find_locked(a, name, want) ||
                 (restore && asset_store_sha256_valid(want) && file_exists(cache)));
    if (!current && !held) {
        if (f == STORE_MISSING)
            asset_refuse(e, ASSETS_INVALID, field,
                         "no asset of that name; PUT /v1/assets/%s first", name);
        else
            asset_refuse(e, ASSETS_CONFLICT, sha_field, "the asset %s is now %s, not the pinned %s",
                         name, r.sha256, want);
        goto out;
    }
    if (current) {
        const char *kind = json_string_value(json_object_get(r.description, "kind"));
        bool is_environment = kind && strcmp(kind, "environment") == 0;
        if (is_environment != environment) {
            asset_refuse(e, ASSETS_INVALID, field,
                         environment ? "%s is a glTF scene, not an environment map (an "
                                       "equirectangular .hdr)"
                                     : "%s is an environment map: name it in "
                                       "look.ibl.environment {\"asset\": ...}, not scene.asset",
                         name);
            goto out;
        }
    }
    if (!want[0])
        memcpy(sha, r.sha256, 65);
    if (!pin_add_locked(a, name, sha)) {
        asset_refuse(e, ASSETS_INTERNAL, field, "out of memory");
        goto out;
    }
    ok = true;
out:
    store_asset_finish(&r);
    return ok;
}

static void unpin_name_locked(struct assets *a, const char *name, const char *sha)
{
    struct asset_pin *p = asset_pin_find_locked(a, name, sha);
    if (p && --p->count == 0) {
        *p = a->pins[--a->npins];
        asset_release_files_locked(a, sha);
    } else if (!p) {
        LOG(LOG_WARN, "assets: %s (%s) unpinned but not pinned", name, sha);
    }
}

/* Does a look's IBL name an environment map among the assets? A job's look
 * and its reference look may. */
static bool names_environment(const struct ibl_spec *ibl)
{
    return ibl->enabled && ibl->environment == IBL_ENV_ASSET;
}

bool assets_pin(struct assets *a, struct job_spec *spec, bool restore, struct assets_error *e)
{
    static const char *const fields[2][2] = {
        {"look.ibl.environment.asset", "look.ibl.environment.asset_sha256"},
        {"reference_look.ibl.environment.asset", "reference_look.ibl.environment.asset_sha256"}};
    struct scene_spec *scene = &spec->scene;
    struct ibl_spec *ibls[2] = {&spec->look.ibl, &spec->reference_look.ibl};
    int envs_pinned = 0;
    bool scene_pinned = false;
    pthread_mutex_lock(&a->lock);
    if (scene->asset[0]) {
        if (!pin_name_locked(a, scene->asset, scene->asset_sha256, false, restore,
                             "scene.asset", "scene.asset_sha256", e))
            goto fail;
        scene_pinned = true;
        scene->asset_bytes = memory_bytes(a, scene->asset_sha256);
    }
    for (; envs_pinned < 2; envs_pinned++) {
        struct ibl_spec *ibl = ibls[envs_pinned];
        if (names_environment(ibl) &&
            !pin_name_locked(a, ibl->env_asset, ibl->env_sha256, true, restore,
                                    fields[envs_pinned][0], fields[envs_pinned][1], e))
            goto fail;
    }
    pthread_mutex_unlock(&a->lock);
    return true;
fail:
    while (envs_pinned-- > 0) {
        if (names_environment(ibls[envs_pinned]))
            unpin_name_locked(a, ibls[envs_pinned]->env_asset, ibls[envs_pinned]->env_sha256);
    }
    if (scene_pinned)
        unpin_name_locked(a, scene->asset, scene->asset_sha256);
    pthread_mutex_unlock(&a->lock);
    return false;
}

void assets_unpin(struct assets *a, const struct job_spec *spec)
{
    const struct ibl_spec *ibls[2] = {&spec->look.ibl, &spec->reference_look.ibl};
    pthread_mutex_lock(&a->lock);
    if (spec->scene.asset[0])
        unpin_name_locked(a, spec->scene.asset, spec->scene.asset_sha256);
    for (int i = 0; i < 2; i++)
        if (names_environment(ibls[i]))
            unpin_name_locked(a, ibls[i]->env_asset, ibls[i]->env_sha256);
    pthread_mutex_unlock(&a->lock);
}

void assets_job_ended(struct assets *a, const struct job_spec *spec)
{
    const struct ibl_spec *ibls[2] = {&spec->look.ibl, &spec->reference_look.ibl};
    pthread_mutex_lock(&a->lock);
    if (spec->scene.asset[0] && spec->scene.asset_sha256[0])
        asset_release_files_locked(a, spec->scene.asset_sha256);
    for (int i = 0; i < 2; i++)
        if (names_environment(ibls[i]) && ibls[i]->env_sha256[0])
            asset_release_files_locked(a, ibls[i]->env_sha256);
    pthread_mutex_unlock(&a->lock);
}

static bool hook_pin(void *ctx, struct job_spec *spec, bool restore, char *field,
                     size_t field_cap, char *message, size_t message_cap)
{
    struct assets_error e;
    if (assets_pin(ctx, spec, restore, &e))
        return true;
    snprintf(field, field_cap, "%s", e.field);
    snprintf(message, message_cap, "%s", e.message);
    return false;
}

static void hook_unpin(void *ctx, const struct job_spec *spec) { assets_unpin(ctx, spec); }

static void hook_ended(void *ctx, const struct job_spec *spec) { assets_job_ended(ctx, spec); }

void assets_queue_hooks(struct assets *a, struct queue_asset_hooks *out)
{
    *out = (struct queue_asset_hooks){.pin = hook_pin, .unpin = hook_unpin,
                                      .ended = hook_ended, .ctx = a};
}
