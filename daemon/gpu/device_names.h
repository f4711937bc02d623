#ifndef SHADEBENCH_DEVICE_NAMES_H
#define SHADEBENCH_DEVICE_NAMES_H

/* The names a lab knows a GPU by, and which EGL device a --device setting
 * names. GL-free: egl.c fills a struct gpu_device_names from each EGL
 * device's strings, device_names_from_sysfs adds what the kernel says of its
 * node (the PCI bus id) and what NVIDIA's driver says of its UUID, and
 * device_spec_match picks one, or fails naming every device there is.
 * The sysfs and procfs paths are read under a root folder ("" in the daemon,
 * a fake tree in the tests). Pure but for those reads; any thread. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

/* Sizes of the names (with their NUL). */
enum {
    DEVICE_NODE_CAP = 64,
    DEVICE_BUS_ID_CAP = 16, /* "0000:01:00.0" */
    DEVICE_UUID_CAP = 40,   /* "xxxxxxxx-xxxx-xxxx-xxxx-xxxxxxxxxxxx" */
};

struct gpu_device_names {
    int index;     /* EGL's enumeration order (eglQueryDevicesEXT) */
    bool software; /* EGL_MESA_device_software: llvmpipe and friends */
    char vendor[64];    /* EGL_VENDOR (EGL_EXT_device_query_name), else GL_VENDOR once probed */
    char renderer[128]; /* EGL_RENDERER_EXT, else GL_RENDERER once probed */
    char driver[64];    /* EGL_DRIVER_NAME_EXT (EGL_EXT_device_persistent_id) */
    char drm_node[DEVICE_NODE_CAP];    /* EGL_DRM_DEVICE_FILE_EXT: /dev/dri/cardN */
    char render_node[DEVICE_NODE_CAP]; /* EGL_DRM_RENDER_NODE_FILE_EXT, else from sysfs */
    char bus_id[DEVICE_BUS_ID_CAP];    /* PCI domain:bus:device.function, lower case */
    char bus_id_from[48];              /* where bus_id came from (sysfs, NVIDIA's procfs) */
    char uuid[DEVICE_UUID_CAP];        /* EGL_DEVICE_UUID_EXT, else NVIDIA's procfs; lower case */
    char uuid_from[48];
    int cuda_device;  /* EGL_CUDA_DEVICE_NV (EGL_NV_device_cuda), else -1 */
    int nvidia_minor; /* NVIDIA's "Device Minor" of its bus id: /dev/nvidiaN; else -1 */
};

/* Zeroes d but for its index, and the numbers a device may lack (-1). */
void device_names_init(struct gpu_device_names *d, int index);

/* Adds, under root, what the kernel and the driver say of d: the PCI bus id
 * of its DRM node (/sys/class/drm/NODE/device), its render node from the bus
 * id (/sys/bus/pci/devices/BUS/drm), and on NVIDIA's driver the bus id of
 * its UUID or the UUID of its bus id (/proc/driver/nvidia/gpus/BUS/information).
 * Names already known are kept. */
void device_names_from_sysfs(struct gpu_device_names *d, const char *root);

/* "0000:01:00.0" from "0000:01:00.0", "00000000:01:00.0" (nvidia-smi),
 * "01:00.0" (domain 0) or "pci:..." in any case; false when it is not one. */
bool device_bus_id_normalize(const char *text, char *out, size_t cap);
/* The 16-byte UUID, written 8-4-4-4-12 in lower case, from "GPU-..."
 * (nvidia-smi, CUDA_VISIBLE_DEVICES), "uuid:..." or 32 hex digits with or
 * without dashes; false when it is not one. */
bool device_uuid_normalize(const char *text, char *out, size_t cap);
/* The same from 16 bytes (EGL_DEVICE_UUID_EXT). */
void device_uuid_from_bytes(const unsigned char bytes[16], char *out, size_t cap);

enum device_spec_kind {
    DEVICE_SPEC_AUTO,      /* the first hardware device, then software, then surfaceless */
    DEVICE_SPEC_INDEX,     /* EGL's index */
    DEVICE_SPEC_NODE,      /* a DRM node, render or primary, or NVIDIA's /dev/nvidiaN */
    DEVICE_SPEC_BUS_ID,    /* a PCI bus id */
    DEVICE_SPEC_UUID,      /* the device's UUID */
    DEVICE_SPEC_ALLOCATED, /* what the batch scheduler gave this process (device_allocated.h) */
};

struct device_spec {
    enum device_spec_kind kind;
    int index;       /* DEVICE_SPEC_INDEX */
    char value[DEVICE_NODE_CAP]; /* normalized node, bus id or UUID */
    char text[128];  /* as given, for messages */
};

/* Parses a --device setting: an index ("0"), a DRM node ("/dev/dri/renderD128",
 * "renderD128", "card1") or NVIDIA's device file ("/dev/nvidia1"), a PCI bus id ("0000:41:00.0", "pci:41:00.0"), a UUID
 * ("GPU-..." or "uuid:..."), "auto" or "allocated". False with err naming
 * the forms. */
bool device_spec_parse(const char *text, struct device_spec *spec, char *err, size_t errlen);
/* The kind's name in results: "auto", "index", "node", "bus_id", "uuid", "allocated". */
const char *device_spec_kind_name(enum device_spec_kind kind);

/* The device of devs[0..n) that spec (not auto or allocated) names: its
 * position in devs, or -1 with err naming what was asked and listing every
 * device with its names ("no EGL device has ..."). */
int device_spec_match(const struct device_spec *spec, const struct gpu_device_names *devs, int n,
                      char *err, size_t errlen);

/* One line: "0: llvmpipe (...) [software], node -, bus id -, uuid -". */
void device_names_line(const struct gpu_device_names *d, char *out, size_t cap);
/* New reference: index, software, vendor, renderer, driver, drm_node,
 * render_node, bus_id (and bus_id_from), uuid (and uuid_from), cuda_device,
 * nvidia_minor;
 * a name the device lacks is null. */
json_t *device_names_json(const struct gpu_device_names *d);

#endif
