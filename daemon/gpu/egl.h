#ifndef SHADEBENCH_EGL_H
#define SHADEBENCH_EGL_H

/* The one headless OpenGL context, on the EGL device a --device setting
 * names (device_names.h): EGL_EXT_platform_device, each device described
 * by what EGL says of it (EGL_EXT_device_drm, EGL_EXT_device_drm_render_node,
 * EGL_EXT_device_persistent_id, EGL_EXT_device_query_name,
 * EGL_NV_device_cuda) and what sysfs and NVIDIA's procfs add (the PCI bus
 * id, the UUID). egl_context_create and egl_probe_device: the thread that
 * will render (the context is made current on it); the rest any thread
 * once the context exists. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "daemon/gpu/device_names.h"

/* Enumerates EGL devices (EGL_EXT_device_enumeration) with their names,
 * without opening any. Returns the count, or -1 with err filled when the
 * extension is missing. */
int egl_list_devices(struct gpu_device_names *out, int max, char *err, size_t errlen);

/* Opens device index briefly for what only a context tells (GL_VENDOR,
 * GL_RENDERER where EGL had no name, GL_VERSION). False with why when it
 * gives no OpenGL 4.3 core context. */
bool egl_probe_device(int index, struct gpu_device_names *d, char *gl_version, size_t cap,
                      char *why, size_t whylen);

struct egl_context;

/* The device spec names (device_names.h): an index, a node, a bus id or a
 * UUID must match one EGL device, which must give a context (else err
 * lists every device); "allocated" reads the scheduler's environment
 * (device_allocated.h); auto tries hardware devices first, then software
 * devices, then EGL_MESA_platform_surfaceless. The context is OpenGL 4.3
 * core, made current on no surface, on the calling thread. */
struct egl_context *egl_context_create(const struct device_spec *spec, bool debug, char *err,
                                       size_t errlen);
void egl_context_destroy(struct egl_context *ctx);

const char *egl_context_platform(const struct egl_context *ctx);
/* Short description of the selected device, e.g. "device 0 /dev/dri/renderD128 (0000:01:00.0)". */
const char *egl_context_device(const struct egl_context *ctx);
const char *egl_context_egl_version(const struct egl_context *ctx);
const char *egl_context_egl_vendor(const struct egl_context *ctx);

/* Adds to device (the result's and /v1/info's "device" object) the opened
 * device's names (egl_device_index, software, drm_node, render_node,
 * bus_id, uuid), "selection" (what was asked, how it was matched, why) and
 * "egl_devices" (every EGL device with its names). With the context current. */
void egl_context_describe(const struct egl_context *ctx, json_t *device);

#endif
