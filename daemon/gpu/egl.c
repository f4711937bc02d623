#define _GNU_SOURCE /* dl_iterate_phdr, RTLD_NODELETE (sanitizer builds) */
#include "daemon/gpu/egl.h"

#include "config.h"

#ifdef SHADEBENCH_SANITIZERS
#include <dlfcn.h>
#include <link.h>
#endif
#include <epoxy/egl.h>
#include <epoxy/gl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "daemon/gpu/device_allocated.h"

/* Newer than the EGL headers libepoxy 1.5 ships with. */
#ifndef EGL_DRM_RENDER_NODE_FILE_EXT
#define EGL_DRM_RENDER_NODE_FILE_EXT 0x3377
#endif
#ifndef EGL_DRIVER_NAME_EXT
#define EGL_DRIVER_NAME_EXT 0x335E
#endif
#ifndef EGL_RENDERER_EXT
#define EGL_RENDERER_EXT 0x335F
#endif

#ifndef EGL_DEVICE_UUID_EXT
#define EGL_DEVICE_UUID_EXT 0x335C
#endif
#ifndef EGL_CUDA_DEVICE_NV
#define EGL_CUDA_DEVICE_NV 0x323A
#endif
typedef EGLBoolean (*query_device_binary_fn)(EGLDeviceEXT device, EGLint name, EGLint max_size,
                                              void *value, EGLint *size);

enum { MAX_DEVICES = 16 };

struct egl_context {
    EGLDisplay display;
    EGLContext context;
    char platform[32];
    char device[192];
    char version[64];
    char vendor[64];
    /* Every EGL device with its names, the one opened (-1: surfaceless),
     * what was asked and why this one. */
    struct gpu_device_names devices[MAX_DEVICES];
    int device_count, selected;
    struct device_spec asked;
    enum device_spec_kind matched_by;
    char why[800];
};

static bool has_word(const char *list, const char *word)
{
    size_t n = strlen(word);
    for (const char *p = list; p && (p = strstr(p, word)); p += n)
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0'))
            return true;
    return false;
}

static const char *client_extensions(void)
{
    const char *ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    return ext ? ext : "";
}

static void copy_str(char *dst, size_t cap, const char *src)
{
    snprintf(dst, cap, "%s", src ? src : "");
}

/* Where sysfs and procfs are read: the real ones, or a fake tree that the
 * tests name (device_sysfs.h). */
static const char *sysfs_root(void)
{
    const char *root = getenv("SHADEBENCH_SYSFS_ROOT");
    return root ? root : "";
}

static int query_devices(EGLDeviceEXT *devices, char *err, size_t errlen)
{
    const char *ext = client_extensions();
    if (!has_word(ext, "EGL_EXT_device_enumeration") &&
        !has_word(ext, "EGL_EXT_device_base")) {
        snprintf(err, errlen, "EGL_EXT_device_enumeration is not available");
        return -1;
    }
    EGLint n = 0;
    if (!eglQueryDevicesEXT(MAX_DEVICES, devices, &n)) {
        snprintf(err, errlen, "eglQueryDevicesEXT failed (0x%x)", eglGetError());
        return -1;
    }
    return n;
}

static void describe_device(EGLDeviceEXT dev, int index, struct gpu_device_names *d)
{
    device_names_init(d, index);
    const char *ext = eglQueryDeviceStringEXT(dev, EGL_EXTENSIONS);
    d->software = has_word(ext, "EGL_MESA_device_software");
    if (has_word(ext, "EGL_EXT_device_drm"))
        copy_str(d->drm_node, sizeof(d->drm_node),
                 eglQueryDeviceStringEXT(dev, EGL_DRM_DEVICE_FILE_EXT));
    if (has_word(ext, "EGL_EXT_device_drm_render_node"))
        copy_str(d->render_node, sizeof(d->render_node),
                 eglQueryDeviceStringEXT(dev, EGL_DRM_RENDER_NODE_FILE_EXT));
    if (has_word(ext, "EGL_EXT_device_persistent_id")) {
        copy_str(d->driver, sizeof(d->driver), eglQueryDeviceStringEXT(dev, EGL_DRIVER_NAME_EXT));
        /* Newer than libepoxy 1.5's table: looked up by name. */
        query_device_binary_fn binary =
            (query_device_binary_fn)eglGetProcAddress("eglQueryDeviceBinaryEXT");
        unsigned char uuid[16];
        EGLint size = 0;
        if (binary && binary(dev, EGL_DEVICE_UUID_EXT, 16, uuid, &size) && size == 16) {
            device_uuid_from_bytes(uuid, d->uuid, sizeof(d->uuid));
            copy_str(d->uuid_from, sizeof(d->uuid_from), "EGL_EXT_device_persistent_id");
        }
    }
    if (has_word(ext, "EGL_EXT_device_query_name")) {
        copy_str(d->vendor, sizeof(d->vendor), eglQueryDeviceStringEXT(dev, EGL_VENDOR));
        copy_str(d->renderer, sizeof(d->renderer), eglQueryDeviceStringEXT(dev, EGL_RENDERER_EXT));
    }
    EGLAttrib cuda = -1;
    if (has_word(ext, "EGL_NV_device_cuda") && eglQueryDeviceAttribEXT(dev, EGL_CUDA_DEVICE_NV, &cuda))
        d->cuda_device = (int)cuda;
    eglGetError(); /* a string the driver lacks is not an error worth keeping */
    device_names_from_sysfs(d, sysfs_root());
}

int egl_list_devices(struct gpu_device_names *out, int max, char *err, size_t errlen)
{
    EGLDeviceEXT devices[MAX_DEVICES];
    int n = query_devices(devices, err, errlen);
    for (int i = 0; i < n && i < max; i++)
        describe_device(devices[i], i, &out[i]);
    return n < max ? n : max;
}

#ifdef SHADEBENCH_SANITIZERS
static int pin_module(struct dl_phdr_info *info, size_t size, void *data)
{
    (void)size, (void)data;
    if (info->dlpi_name && info->dlpi_name[0])
        dlopen(info->dlpi_name, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
    return 0;
}
#endif

/* Sanitizer builds only: Mesa unloads its driver when the GL context goes
 * (a brief one for --list-devices or a start-up error, or the daemon's
 * own), and memory that only the driver's globals pointed to then looks
 * leaked, with no module to name in a suppression. Marking every library
 * loaded by now (the driver and LLVM included) as never to be unloaded
 * keeps it reachable, so LeakSanitizer reports the daemon's own leaks only. */
static void pin_loaded_modules(void)
{
#ifdef SHADEBENCH_SANITIZERS
    dl_iterate_phdr(pin_module, NULL);
#endif
}

static bool init_context(struct egl_context *ctx, EGLDisplay display, bool debug,
                         char *err, size_t errlen)
{
    EGLint major, minor;
    if (display == EGL_NO_DISPLAY || !eglInitialize(display, &major, &minor)) {
        snprintf(err, errlen, "eglInitialize failed (0x%x)", eglGetError());
        return false;
    }
    ctx->display = display;
    copy_str(ctx->version, sizeof(ctx->version), eglQueryString(display, EGL_VERSION));
    copy_str(ctx->vendor, sizeof(ctx->vendor), eglQueryString(display, EGL_VENDOR));
    const char *dpy_ext = eglQueryString(display, EGL_EXTENSIONS);
    if (!has_word(dpy_ext, "EGL_KHR_surfaceless_context")) {
        snprintf(err, errlen, "EGL_KHR_surfaceless_context is not supported");
        goto fail;
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
        snprintf(err, errlen, "eglBindAPI(EGL_OPENGL_API) failed (0x%x)", eglGetError());
        goto fail;
    }
    /* Rendering goes to FBOs, so any config will do; no-config avoids
     * depending on pbuffer support where the driver offers it. */
    EGLConfig config = NULL;
    if (!has_word(dpy_ext, "EGL_KHR_no_config_context")) {
        static const EGLint attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        EGLint count = 0;
        if (!eglChooseConfig(display, attribs, &config, 1, &count) || count < 1) {
            snprintf(err, errlen, "no EGL config supports desktop OpenGL");
            goto fail;
        }
    }
    const EGLint attribs[] = {
        EGL_CONTEXT_MAJOR_VERSION, 4,
        EGL_CONTEXT_MINOR_VERSION, 3,
        EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
        EGL_CONTEXT_OPENGL_DEBUG, debug ? EGL_TRUE : EGL_FALSE,
        EGL_NONE,
    };
    ctx->context = eglCreateContext(display, config, EGL_NO_CONTEXT, attribs);
    if (ctx->context == EGL_NO_CONTEXT) {
        snprintf(err, errlen, "no OpenGL 4.3 core context (eglCreateContext 0x%x)",
                 eglGetError());
        goto fail;
    }
    if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx->context)) {
        snprintf(err, errlen, "eglMakeCurrent failed (0x%x)", eglGetError());
        goto fail;
    }
    pin_loaded_modules();
    if (epoxy_gl_version() < 43) {
        snprintf(err, errlen, "OpenGL %d.%d is too old: 4.3 is needed",
                 epoxy_gl_version() / 10, epoxy_gl_version() % 10);
        goto fail;
    }
    return true;
fail:
    if (ctx->context != EGL_NO_CONTEXT) {
        eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        eglDestroyContext(display, ctx->context);
        ctx->context = EGL_NO_CONTEXT;
    }
    eglTerminate(display);
    ctx->display = EGL_NO_DISPLAY;
    return false;
}

static bool try_device(struct egl_context *ctx, EGLDeviceEXT dev, int index, bool debug,
                       char *err, size_t errlen)
{
    const struct gpu_device_names *d = &ctx->devices[index];
    EGLDisplay dpy = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, dev, NULL);
    if (!init_context(ctx, dpy, debug, err, errlen)) {
        LOG(LOG_INFO, "EGL device %d: %s", index, err);
        return false;
    }
    ctx->selected = index;
    copy_str(ctx->platform, sizeof(ctx->platform), "device");
    const char *node = d->render_node[0] ? d->render_node : d->drm_node;
    snprintf(ctx->device, sizeof(ctx->device), "device %d%s%s%s%s%s", index, node[0] ? " " : "",
             node, d->bus_id[0] ? " (" : "", d->bus_id, d->bus_id[0] ? ")" : "");
    if (d->software)
        snprintf(ctx->device + strlen(ctx->device), sizeof(ctx->device) - strlen(ctx->device),
                 " (software)");
    return true;
}

/* Opens dev briefly for GL_VENDOR, GL_RENDERER (where EGL had no names)
 * and GL_VERSION, and closes it again. */
static bool probe_names(EGLDeviceEXT dev, struct gpu_device_names *d, char *gl_version,
                        size_t cap, char *why, size_t whylen)
{
    struct egl_context probe = {.display = EGL_NO_DISPLAY, .context = EGL_NO_CONTEXT};
    EGLDisplay dpy = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, dev, NULL);
    if (!init_context(&probe, dpy, false, why, whylen))
        return false;
    if (!d->vendor[0])
        copy_str(d->vendor, sizeof(d->vendor), (const char *)glGetString(GL_VENDOR));
    if (!d->renderer[0])
        copy_str(d->renderer, sizeof(d->renderer), (const char *)glGetString(GL_RENDERER));
    if (gl_version)
        copy_str(gl_version, cap, (const char *)glGetString(GL_VERSION));
    eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(dpy, probe.context);
    eglTerminate(dpy);
    return true;
}

static const char *env_get(const char *name, void *unused)
{
    (void)unused;
    return getenv(name);
}

/* Auto: hardware first, then software, then surfaceless. A lab box with a
 * GPU must never silently fall back to a CPU renderer just because the
 * software device is listed first. */
static bool open_auto(struct egl_context *ctx, EGLDeviceEXT *devices, bool debug, char *why,
                      size_t whylen)
{
    for (int pass = 0; pass < 2; pass++)
        for (int i = 0; i < ctx->device_count; i++) {
            if (ctx->devices[i].software != (pass == 1))
                continue;
            if (try_device(ctx, devices[i], i, debug, why, whylen)) {
                snprintf(ctx->why + strlen(ctx->why), sizeof(ctx->why) - strlen(ctx->why),
                         "%sthe first %s EGL device that gave an OpenGL 4.3 core context%s",
                         ctx->why[0] ? ": " : "", pass ? "software" : "hardware",
                         pass ? " (no hardware device did)" : "");
                return true;
            }
        }
    if (has_word(client_extensions(), "EGL_MESA_platform_surfaceless")) {
        EGLDisplay dpy = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA,
                                                  EGL_DEFAULT_DISPLAY, NULL);
        if (init_context(ctx, dpy, debug, why, whylen)) {
            copy_str(ctx->platform, sizeof(ctx->platform), "surfaceless");
            copy_str(ctx->device, sizeof(ctx->device), "EGL_MESA_platform_surfaceless");
            snprintf(ctx->why + strlen(ctx->why), sizeof(ctx->why) - strlen(ctx->why),
                     "%sno EGL device gave a context: EGL_MESA_platform_surfaceless",
                     ctx->why[0] ? ": " : "");
            return true;
        }
    }
    return false;
}

struct egl_context *egl_context_create(const struct device_spec *spec, bool debug, char *err,
                                       size_t errlen)
{
    struct egl_context *ctx = calloc(1, sizeof(*ctx));
    if (!ctx) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    ctx->display = EGL_NO_DISPLAY;
    ctx->context = EGL_NO_CONTEXT;
    ctx->selected = -1;
    ctx->asked = *spec;
    const char *ext = client_extensions();
    bool platform_device = has_word(ext, "EGL_EXT_platform_device");

    EGLDeviceEXT devices[MAX_DEVICES];
    char why[1024] = "";
    int n = platform_device ? query_devices(devices, why, sizeof(why)) : -1;
    for (int i = 0; i < n; i++)
        describe_device(devices[i], i, &ctx->devices[i]);
    ctx->device_count = n > 0 ? n : 0;

    struct device_spec named = *spec;
    const char *asked = spec->kind == DEVICE_SPEC_ALLOCATED ? "allocated"
                        : spec->kind == DEVICE_SPEC_AUTO    ? "auto"
                                                            : spec->text;
    if (spec->kind == DEVICE_SPEC_ALLOCATED) {
        struct device_allocation a;
        if (!device_allocated(env_get, NULL, sysfs_root(), &a, why, sizeof(why))) {
            snprintf(err, errlen, "--device allocated: %s", why);
            goto fail;
        }
        copy_str(ctx->why, sizeof(ctx->why), a.why);
        named = a.named ? a.spec : (struct device_spec){.kind = DEVICE_SPEC_AUTO};
    }
    ctx->matched_by = named.kind;
    if (named.kind == DEVICE_SPEC_AUTO) {
        if (open_auto(ctx, devices, debug, why, sizeof(why)))
            return ctx;
        snprintf(err, errlen, "no EGL device or surfaceless platform gave an OpenGL 4.3 "
                 "core context (last error: %s)", why[0] ? why : "none tried");
        goto fail;
    }
    if (n < 0) {
        snprintf(err, errlen, "--device %s: EGL device platform unavailable: %s", asked,
                 platform_device ? why : "no EGL_EXT_platform_device");
        goto fail;
    }
    char list[2048];
    int index = device_spec_match(&named, ctx->devices, ctx->device_count, list, sizeof(list));
    if (index < 0) {
        /* Name what there is by its renderer too: the daemon does not
         * start, so opening each device briefly costs nothing that runs. */
        for (int i = 0; i < ctx->device_count; i++)
            if (!ctx->devices[i].renderer[0])
                probe_names(devices[i], &ctx->devices[i], NULL, 0, why, sizeof(why));
        device_spec_match(&named, ctx->devices, ctx->device_count, list, sizeof(list));
        snprintf(err, errlen, "--device %s: %s", asked, list);
        goto fail;
    }
    if (!try_device(ctx, devices[index], index, debug, why, sizeof(why))) {
        snprintf(err, errlen, "--device %s: EGL device %d gave no context: %s", asked, index, why);
        goto fail;
    }
    if (spec->kind != DEVICE_SPEC_ALLOCATED)
        snprintf(ctx->why, sizeof(ctx->why), "--device %s: EGL device %d has that %s", asked,
                 index, named.kind == DEVICE_SPEC_INDEX ? "index"
                        : named.kind == DEVICE_SPEC_NODE ? "device node"
                        : named.kind == DEVICE_SPEC_BUS_ID ? "PCI bus id" : "UUID");
    return ctx;
fail:
    free(ctx);
    return NULL;
}

bool egl_probe_device(int index, struct gpu_device_names *d, char *gl_version, size_t cap,
                      char *why, size_t whylen)
{
    EGLDeviceEXT devices[MAX_DEVICES];
    int n = query_devices(devices, why, whylen);
    if (index >= n) {
        if (n >= 0)
            snprintf(why, whylen, "no EGL device %d", index);
        return false;
    }
    return probe_names(devices[index], d, gl_version, cap, why, whylen);
}

void egl_context_destroy(struct egl_context *ctx)
{
    if (!ctx)
        return;
    if (ctx->display != EGL_NO_DISPLAY) {
        eglMakeCurrent(ctx->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (ctx->context != EGL_NO_CONTEXT)
            eglDestroyContext(ctx->display, ctx->context);
        eglTerminate(ctx->display);
    }
    free(ctx);
}

const char *egl_context_platform(const struct egl_context *ctx) { return ctx->platform; }
const char *egl_context_device(const struct egl_context *ctx) { return ctx->device; }
const char *egl_context_egl_version(const struct egl_context *ctx) { return ctx->version; }
const char *egl_context_egl_vendor(const struct egl_context *ctx) { return ctx->vendor; }

void egl_context_describe(const struct egl_context *ctx, json_t *device)
{
    json_t *all = json_array();
    for (int i = 0; i < ctx->device_count; i++) {
        struct gpu_device_names d = ctx->devices[i];
        /* Only the opened device's GL strings are known: the others are
         * not opened, so that a daemon never claims memory on a GPU that
         * another task was given. */
        if (i == ctx->selected) {
            if (!d.vendor[0])
                copy_str(d.vendor, sizeof(d.vendor), (const char *)glGetString(GL_VENDOR));
            if (!d.renderer[0])
                copy_str(d.renderer, sizeof(d.renderer), (const char *)glGetString(GL_RENDERER));
        }
        json_t *j = device_names_json(&d);
        json_object_set_new(j, "selected", json_boolean(i == ctx->selected));
        if (i == ctx->selected) {
            static const char *const keys[] = {"software", "drm_node", "render_node", "bus_id",
                                               "uuid"};
            for (size_t k = 0; k < sizeof(keys) / sizeof(keys[0]); k++)
                json_object_set(device, keys[k], json_object_get(j, keys[k]));
        }
        json_array_append_new(all, j);
    }
    json_object_set_new(device, "egl_device_index",
                        ctx->selected >= 0 ? json_integer(ctx->selected) : json_null());
    const char *asked = ctx->asked.kind == DEVICE_SPEC_AUTO        ? "auto"
                        : ctx->asked.kind == DEVICE_SPEC_ALLOCATED ? "allocated"
                                                                   : ctx->asked.text;
    json_object_set_new(device, "selection",
                        json_pack("{s:s, s:s, s:s}", "asked", asked, "matched_by",
                                  device_spec_kind_name(ctx->matched_by), "why", ctx->why));
    json_object_set_new(device, "egl_devices", all);
}
