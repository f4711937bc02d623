#define _POSIX_C_SOURCE 200809L
#include "daemon/gpu/egl.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"

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

enum { MAX_DEVICES = 16 };

struct egl_context {
    EGLDisplay display;
    EGLContext context;
    char platform[32];
    char device[192];
    char version[64];
    char vendor[64];
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

static void describe_device(EGLDeviceEXT dev, int index, struct egl_device_info *info)
{
    memset(info, 0, sizeof(*info));
    info->index = index;
    const char *ext = eglQueryDeviceStringEXT(dev, EGL_EXTENSIONS);
    copy_str(info->extensions, sizeof(info->extensions), ext);
    info->software = has_word(ext, "EGL_MESA_device_software");
    if (has_word(ext, "EGL_EXT_device_drm"))
        copy_str(info->drm_node, sizeof(info->drm_node),
                 eglQueryDeviceStringEXT(dev, EGL_DRM_DEVICE_FILE_EXT));
    if (has_word(ext, "EGL_EXT_device_drm_render_node"))
        copy_str(info->render_node, sizeof(info->render_node),
                 eglQueryDeviceStringEXT(dev, EGL_DRM_RENDER_NODE_FILE_EXT));
    if (has_word(ext, "EGL_EXT_device_persistent_id"))
        copy_str(info->driver, sizeof(info->driver),
                 eglQueryDeviceStringEXT(dev, EGL_DRIVER_NAME_EXT));
    if (has_word(ext, "EGL_EXT_device_query_name"))
        copy_str(info->renderer, sizeof(info->renderer),
                 eglQueryDeviceStringEXT(dev, EGL_RENDERER_EXT));
    eglGetError(); /* a string the driver lacks is not an error worth keeping */
}

int egl_list_devices(struct egl_device_info *out, int max, char *err, size_t errlen)
{
    EGLDeviceEXT devices[MAX_DEVICES];
    int n = query_devices(devices, err, errlen);
    for (int i = 0; i < n && i < max; i++)
        describe_device(devices[i], i, &out[i]);
    return n < max ? n : max;
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

static bool try_device(struct egl_context *ctx, EGLDeviceEXT dev, int index,
                       bool debug, char *err, size_t errlen)
{
    struct egl_device_info info;
    describe_device(dev, index, &info);
    EGLDisplay dpy = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, dev, NULL);
    if (!init_context(ctx, dpy, debug, err, errlen)) {
        LOG(LOG_INFO, "EGL device %d: %s", index, err);
        return false;
    }
    copy_str(ctx->platform, sizeof(ctx->platform), "device");
    const char *node = info.render_node[0] ? info.render_node : info.drm_node;
    snprintf(ctx->device, sizeof(ctx->device), "device %d%s%s%s", index,
             node[0] ? " " : "", node, info.software ? " (software)" : "");
    return true;
}

struct egl_context *egl_context_create(int device, bool debug, char *err,
                                       size_t errlen)
{
    struct egl_context *ctx = calloc(1, sizeof(*ctx));
    if (!ctx) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    ctx->display = EGL_NO_DISPLAY;
    ctx->context = EGL_NO_CONTEXT;
    const char *ext = client_extensions();
    bool platform_device = has_word(ext, "EGL_EXT_platform_device");

    EGLDeviceEXT devices[MAX_DEVICES];
    char why[256] = "";
    int n = platform_device ? query_devices(devices, why, sizeof(why)) : -1;
    if (device >= 0) {
        if (n < 0) {
            snprintf(err, errlen, "--device %d: EGL device platform unavailable: %s",
                     device, platform_device ? why : "no EGL_EXT_platform_device");
            goto fail;
        }
        if (device >= n) {
            snprintf(err, errlen, "--device %d: only %d EGL device(s) found", device, n);
            goto fail;
        }
        if (!try_device(ctx, devices[device], device, debug, why, sizeof(why))) {
            snprintf(err, errlen, "--device %d: %s", device, why);
            goto fail;
        }
        return ctx;
    }
    /* Hardware first: a lab box with a GPU must never silently fall back to
     * a CPU renderer just because the software device is listed first. */
    for (int pass = 0; pass < 2; pass++)
        for (int i = 0; i < n; i++) {
            struct egl_device_info info;
            describe_device(devices[i], i, &info);
            if (info.software != (pass == 1))
                continue;
            if (try_device(ctx, devices[i], i, debug, why, sizeof(why)))
                return ctx;
        }
    if (has_word(ext, "EGL_MESA_platform_surfaceless")) {
        EGLDisplay dpy = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA,
                                                  EGL_DEFAULT_DISPLAY, NULL);
        if (init_context(ctx, dpy, debug, why, sizeof(why))) {
            copy_str(ctx->platform, sizeof(ctx->platform), "surfaceless");
            copy_str(ctx->device, sizeof(ctx->device), "EGL_MESA_platform_surfaceless");
            return ctx;
        }
    }
    snprintf(err, errlen, "no EGL device or surfaceless platform gave an OpenGL 4.3 "
             "core context (last error: %s)", why[0] ? why : "none tried");
fail:
    free(ctx);
    return NULL;
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
