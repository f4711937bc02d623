#ifndef SHADEBENCH_EGL_H
#define SHADEBENCH_EGL_H

#include <stdbool.h>
#include <stddef.h>

struct egl_device_info {
    int index;
    bool software;       /* EGL_MESA_device_software: llvmpipe and friends */
    char driver[64];     /* EGL_DRIVER_NAME_EXT where the driver has it */
    char renderer[128];  /* EGL_RENDERER_EXT, or GL_RENDERER once probed */
    char drm_node[128];  /* EGL_DRM_DEVICE_FILE_EXT */
    char render_node[128];
    char extensions[512];
};

/* Enumerates EGL devices (EGL_EXT_device_enumeration). Returns the count,
 * or -1 with err filled when the extension is missing. */
int egl_list_devices(struct egl_device_info *out, int max, char *err, size_t errlen);

struct egl_context;

/* device >= 0 picks that EGL device and fails if it cannot give a context;
 * device < 0 tries hardware devices first, then software devices, then
 * EGL_MESA_platform_surfaceless. The context is OpenGL 4.3 core, made
 * current on no surface, on the calling thread. */
struct egl_context *egl_context_create(int device, bool debug, char *err,
                                       size_t errlen);
void egl_context_destroy(struct egl_context *ctx);

const char *egl_context_platform(const struct egl_context *ctx);
/* Short description of the selected device, e.g. "device 0 (/dev/dri/renderD128)". */
const char *egl_context_device(const struct egl_context *ctx);
const char *egl_context_egl_version(const struct egl_context *ctx);
const char *egl_context_egl_vendor(const struct egl_context *ctx);

#endif
