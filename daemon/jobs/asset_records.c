/* closefrom (glibc 2.34) and O_NOFOLLOW. */
#define _GNU_SOURCE
/* The assets: their files under STATE_DIR/assets, their records in the
 * store, and the reads, deletes and a job's resolution (assets.h). */
#include "daemon/jobs/assets_impl.h"

#include <errno.h>
#include <nettle/sha2.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/clock.h"
#include "common/log.h"

void asset_path(const struct assets *a, const char *sha, const char *ext, char *out,
                size_t cap)
{
    snprintf(out, cap, "%s/%s.%s", a->dir, sha, ext);
}

bool file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

void asset_release_files_locked(struct assets *a, const char *sha)
{
    if (!asset_store_sha256_valid(sha) || strcmp(a->busy_sha, sha) == 0)
        return;
    for (struct task *t = a->tasks; t; t = t->next)
        if (strcmp(t->sha256, sha) == 0)
            return;
    if (asset_pin_find_locked(a, NULL, sha))
        return;
    char job[RECORD_ID_LEN];
    if (store_asset_hash_refs(a->store, sha) != 0 || queue_asset_in_use(a->queue, NULL, sha, job))
        return;
    static const char *const exts[] = {"glb", "gltf", "hdr", "exr", ASSET_CACHE_EXT, "json"};
    for (size_t i = 0; i < sizeof(exts) / sizeof(exts[0]); i++) {
        char path[PATH_MAX + 80];
        asset_path(a, sha, exts[i], path, sizeof(path));
        if (unlink(path) != 0 && errno != ENOENT)
            LOG(LOG_WARN, "assets: cannot remove %s: %s", path, strerror(errno));
    }
}

/* The API adds the record's url after read_only. */
static json_t *record_json(const struct store_asset *r, bool full)
{
    json_t *o = json_pack("{s:s, s:s, s:I, s:s, s:f, s:f, s:s, s:b}", "name", r->name,
                          "sha256", r->sha256, "size", (json_int_t)r->size, "format", r->ext,
                          "created", r->created, "updated", r->updated, "source",
                          r->from_dir ? "asset-dir" : "upload", "read_only", r->from_dir);
    if (!o)
        return NULL;
    if (full) {
        json_object_set(o, "description", r->description ? r->description : json_null());
        return o;
    }
    /* A list shows counts only: the description's arrays as their sizes,
     * its numbers as they are. */
    json_t *summary = json_object();
    static const char *const keys[] = {"meshes", "triangles", "vertices", "materials",
                                       "textures", "images", "lights", "cameras",
                                       "kind", "width", "height"};
    for (size_t i = 0; summary && i < sizeof(keys) / sizeof(keys[0]); i++) {
        json_t *v = json_object_get(r->description, keys[i]);
        if (json_is_array(v))
            json_object_set_new(summary, keys[i], json_integer((json_int_t)json_array_size(v)));
        else if (json_is_object(v) && json_is_integer(json_object_get(v, "count")))
            json_object_set(summary, keys[i], json_object_get(v, "count"));
        else if (json_is_number(v) || json_is_string(v))
            json_object_set(summary, keys[i], v);
    }
    json_object_set_new(o, "summary", summary ? summary : json_null());
    return o;
}

/* Under a->lock: the record of name now points at sha. The files of the
 * hash it pointed at before go when nothing else needs them. *replaced:
 * the name had a record. */
bool asset_put_record_locked(struct assets *a, const struct task *t, const json_t *description,
                             bool *replaced, struct assets_error *e)
{
    struct store_asset old;
    enum store_found f = store_asset_get(a->store, t->name, &old);
    if (f == STORE_ERROR) {
        asset_refuse(e, ASSETS_INTERNAL, "store", "cannot read the asset records (see the log)");
        return false;
    }
    *replaced = f == STORE_FOUND;
    if (f == STORE_FOUND && old.from_dir && t->kind == TASK_UPLOAD) {
        store_asset_finish(&old);
        asset_refuse(e, ASSETS_READ_ONLY, "name",
                     "%s comes from the asset directory (--asset-dir): it cannot "
                     "be replaced over HTTP", t->name);
        return false;
    }
    struct store_asset r = {.size = t->size, .from_dir = t->kind == TASK_DIR,
                            .description = (json_t *)description};
    snprintf(r.name, sizeof(r.name), "%s", t->name);
    snprintf(r.sha256, sizeof(r.sha256), "%s", t->sha256);
    snprintf(r.ext, sizeof(r.ext), "%s", t->ext);
    r.created = r.updated = clock_unix_s();
    char err[PATH_MAX + 300];
    bool ok = store_asset_put(a->store, &r, err, sizeof(err));
    if (!ok) {
        LOG(LOG_ERROR, "assets: %s", err);
        bool full = strstr(err, "full") || strstr(err, "No space");
        asset_refuse(e, full ? ASSETS_NO_SPACE : ASSETS_INTERNAL, "state_dir", "%.480s", err);
    } else if (f == STORE_FOUND && strcmp(old.sha256, t->sha256) != 0) {
        asset_release_files_locked(a, old.sha256);
    }
    store_asset_finish(&old);
    return ok;
}

bool asset_dir_not_ready_locked(struct assets *a, const char *name, const char *field,
                                struct assets_error *e)
{
    struct dir_entry *d = asset_dir_find(a, name);
    if (d && d->state == DIR_PENDING) {
        asset_refuse(e, ASSETS_CONFLICT, field,
                     "%s (from --asset-dir) is being converted; retry shortly", name);
        return true;
    }
    if (d && d->state == DIR_FAILED) {
        asset_refuse(e, ASSETS_UNCONVERTIBLE, field,
                     "%s (from --asset-dir) could not be converted: %.400s", name,
                     d->error);
        return true;
    }
    return false;
}

json_t *assets_describe(struct assets *a, const char *name, struct assets_error *e)
{
    if (!scene_asset_name_valid(name)) {
        asset_refuse(e, ASSETS_INVALID, "name",
                     "an asset name is 1 to %d letters, digits, '.', '_' or '-', "
                     "not starting with '.'", SCENE_ASSET_NAME_MAX);
        return NULL;
    }
    pthread_mutex_lock(&a->lock);
    bool not_ready = asset_dir_not_ready_locked(a, name, "name", e);
    pthread_mutex_unlock(&a->lock);
    if (not_ready)
        return NULL;
    struct store_asset r;
    enum store_found f = store_asset_get(a->store, name, &r);
    json_t *o = f == STORE_FOUND ? record_json(&r, true) : NULL;
    store_asset_finish(&r);
    if (f == STORE_MISSING)
        asset_refuse(e, ASSETS_NOT_FOUND, "name",
                     "no asset of that name (GET /v1/assets lists them)");
    else if (!o)
        asset_refuse(e, ASSETS_INTERNAL, "store", "cannot read the asset records (see the log)");
    return o;
}

static void list_row(void *ctx, const struct store_asset *r)
{
    json_array_append_new(ctx, record_json(r, false));
}

bool assets_list(struct assets *a, const char *cursor, int limit, struct assets_page *page,
                 struct assets_error *e)
{
    memset(page, 0, sizeof(*page));
    json_t *items = json_array();
    char err[PATH_MAX + 300];
    if (!items || !store_asset_list(a->store, cursor, limit, false, list_row, items, page->next,
                                    err, sizeof(err))) {
        json_decref(items);
        asset_refuse(e, ASSETS_INTERNAL, "store", "%.480s", items ? err : "out of memory");
        return false;
    }
    page->items = items;
    pthread_mutex_lock(&a->lock);
    for (size_t i = 0; i < a->ndir; i++) {
        page->converting += a->dir_entries[i].state == DIR_PENDING;
        page->failed += a->dir_entries[i].state == DIR_FAILED;
    }
    pthread_mutex_unlock(&a->lock);
    return true;
}

json_t *assets_delete(struct assets *a, const char *name, struct assets_error *e)
{
    if (!scene_asset_name_valid(name)) {
        asset_refuse(e, ASSETS_INVALID, "name",
                     "an asset name is 1 to %d letters, digits, '.', '_' or '-', "
                     "not starting with '.'", SCENE_ASSET_NAME_MAX);
        return NULL;
    }
    json_t *out = NULL;
    struct store_asset r;
    memset(&r, 0, sizeof(r));
    pthread_mutex_lock(&a->lock);
    if (!asset_writable_locked(a, name, e))
        goto out;
    enum store_found f = store_asset_get(a->store, name, &r);
    if (f != STORE_FOUND) {
        asset_refuse(e, f == STORE_MISSING ? ASSETS_NOT_FOUND : ASSETS_INTERNAL, "name",
                     f == STORE_MISSING ? "no asset of that name (GET /v1/assets lists them)"
                                        : "cannot read the asset records (see the log)");
        goto out;
    }
    char job[RECORD_ID_LEN];
    if (queue_asset_in_use(a->queue, name, NULL, job)) {
        asset_refuse(e, ASSETS_CONFLICT, "name",
                     "job %s (queued or running) uses %s: cancel it or wait for it "
                     "to end (DELETE /v1/jobs/%s)", job, name, job);
        goto out;
    }
    /* A sweep that runs on it, or a job being accepted on it this moment. */
    if (asset_pin_find_locked(a, name, NULL)) {
        asset_refuse(e, ASSETS_CONFLICT, "name",
                     "a queued or running sweep (or a job being accepted) uses %s: cancel the "
                     "sweep or wait for it to end (GET /v1/sweeps?status=running)", name);
        goto out;
    }
    char err[PATH_MAX + 300];
    if (!store_asset_delete(a->store, name, err, sizeof(err))) {
        asset_refuse(e, ASSETS_INTERNAL, "store", "%.480s", err);
        goto out;
    }
    asset_release_files_locked(a, r.sha256);
    LOG(LOG_INFO, "assets: deleted %s (%s)", name, r.sha256);
    out = json_pack("{s:s, s:s, s:s}", "name", name, "sha256", r.sha256, "status", "deleted");
out:
    pthread_mutex_unlock(&a->lock);
    store_asset_finish(&r);
    return out;
}

/* name's stored hash into sha (pinned: must equal it), when the asset is
 * of the kind asked for (an environment map or a glTF scene). field and
 * sha_field name what the job called it. */
static bool resolve_name(struct assets *a, const char *name, char sha[65], bool environment,
                         const char *field, const char *sha_field, struct assets_error *e)
{
    pthread_mutex_lock(&a->lock);
    bool not_ready = asset_dir_not_ready_locked(a, name, field, e);
    pthread_mutex_unlock(&a->lock);
    if (not_ready)
        return false;
    struct store_asset r;
    enum store_found f = store_asset_get(a->store, name, &r);
    bool ok = false;
    const char *kind = f == STORE_FOUND
                           ? json_string_value(json_object_get(r.description, "kind"))
                           : NULL;
    bool is_environment = kind && strcmp(kind, "environment") == 0;
    if (f == STORE_MISSING)
        asset_refuse(e, ASSETS_INVALID, field, "no asset of that name; PUT /v1/assets/%s first",
                     name);
    else if (f == STORE_ERROR)
        asset_refuse(e, ASSETS_INTERNAL, field, "cannot read the asset records (see the log)");
    else if (is_environment != environment)
        asset_refuse(e, ASSETS_INVALID, field,
                     environment ? "%s is a glTF scene, not an environment map (an "
                                   "equirectangular .hdr or .exr)"
                                 : "%s is an environment map: name it in "
                                   "look.ibl.environment {\"asset\": ...}, not scene.asset",
                     name);
    else if (sha[0] && strcmp(sha, r.sha256) != 0)
        asset_refuse(e, ASSETS_CONFLICT, sha_field, "the asset %s is now %s, not the pinned %s",
                     name, r.sha256, sha);
    else {
        memcpy(sha, r.sha256, 65);
        ok = true;
    }
    store_asset_finish(&r);
    return ok;
}

bool assets_resolve(struct assets *a, struct scene_spec *scene, struct assets_error *e)
{
    if (!scene->asset[0])
        return true;
    return resolve_name(a, scene->asset, scene->asset_sha256, false, "scene.asset",
                        "scene.asset_sha256", e);
}
