#ifndef SHADEBENCH_DEVICE_SYSFS_H
#define SHADEBENCH_DEVICE_SYSFS_H

/* What the kernel and the GPU drivers say of a box's GPUs, read from sysfs
 * and procfs under a root folder ("" for the real ones, a fake tree in the
 * tests): the PCI bus id of a DRM node and the nodes of a bus id
 * (/sys/class/drm, /sys/bus/pci/devices), NVIDIA's GPUs with their device
 * minor and UUID (/proc/driver/nvidia/gpus/BUS/information), and AMD's as
 * ROCm numbers them (/sys/class/kfd/kfd/topology/nodes). GL-free; any thread. */

#include <stdbool.h>
#include <stddef.h>

/* One GPU of NVIDIA's driver. */
struct sysfs_nvidia_gpu {
    char bus_id[16]; /* "0000:41:00.0": the folder's name, normalized */
    char uuid[40];   /* normalized (device_names.h), "" when the file has none */
    int minor;       /* "Device Minor": /dev/nvidiaN; -1 when absent */
    char model[96];
};

/* NVIDIA's GPUs, sorted by bus id (the order nvidia-smi and CUDA with
 * CUDA_DEVICE_ORDER=PCI_BUS_ID give them): their count, at most max; 0
 * where the driver is not loaded. */
int sysfs_nvidia_gpus(const char *root, struct sysfs_nvidia_gpu *out, int max);

/* One GPU node of AMD's KFD topology. */
struct sysfs_kfd_gpu {
    int node;          /* the topology node's number */
    int render_minor;  /* drm_render_minor: /dev/dri/renderD<minor> */
    unsigned long long unique_id; /* ROCm's UUID is "GPU-" and its 16 hex digits */
    char bus_id[16];   /* from domain and location_id, "" when absent */
};

/* AMD's GPUs in the order ROCm numbers them (ROCR_VISIBLE_DEVICES,
 * GPU_DEVICE_ORDINAL): the topology nodes that have a GPU (gpu_id not 0),
 * by node number; their count, at most max; 0 without the KFD driver. */
int sysfs_kfd_gpus(const char *root, struct sysfs_kfd_gpu *out, int max);

/* The minors of the box's DRM render nodes (/sys/class/drm/renderD*),
 * ascending; their count, at most max. */
int sysfs_render_minors(const char *root, int *out, int max);

/* The PCI bus id of a DRM node ("/dev/dri/renderD128" or "card0"):
 * PCI_SLOT_NAME of its device's uevent, else the name its device link
 * points to. False when sysfs has no PCI device for it. */
bool sysfs_drm_bus_id(const char *root, const char *node, char *bus, size_t cap);

/* The render node ("/dev/dri/renderD128") and primary node of the PCI
 * device bus, from /sys/bus/pci/devices/BUS/drm; false when it has none. */
bool sysfs_bus_drm_nodes(const char *root, const char *bus, char *render, size_t rcap,
                         char *primary, size_t pcap);

#endif
