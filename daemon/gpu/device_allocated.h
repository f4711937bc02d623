#ifndef SHADEBENCH_DEVICE_ALLOCATED_H
#define SHADEBENCH_DEVICE_ALLOCATED_H

/* --device allocated: the GPU a batch scheduler gave this process, as a
 * device spec (device_names.h) that names it the way EGL's devices can be
 * matched, and why. Read in this order, the first that names a GPU wins:
 *
 *   SLURM_STEP_GPUS, SLURM_JOB_GPUS  Slurm's global GPU indices (not
 *       renumbered by the device cgroup): index i is /dev/nvidia<i> on
 *       NVIDIA's driver (gres.conf File=/dev/nvidia[..]), else the box's
 *       i-th DRM render node (File=/dev/dri/renderD[..]);
 *   CUDA_VISIBLE_DEVICES  a UUID (GPU-...), or an index into NVIDIA's GPUs
 *       in PCI bus order;
 *   ROCR_VISIBLE_DEVICES, GPU_DEVICE_ORDINAL  an index into ROCm's GPUs
 *       (the KFD topology's GPU nodes) or a ROCm UUID (GPU-<16 hex>);
 *       GPU_DEVICE_ORDINAL falls back to NVIDIA's order without KFD;
 *   the device cgroup (v1 devices.list) when it allows a GPU's device file
 *       and not every device.
 *
 * The environment is read through a function (getenv in the daemon, a
 * table in the tests) and the kernel's files under root (device_sysfs.h).
 * GL-free; any thread. */

#include <stdbool.h>
#include <stddef.h>

#include "daemon/gpu/device_names.h"

typedef const char *(*device_env_fn)(const char *name, void *ctx);

struct device_allocation {
    bool named;              /* something in the environment names a GPU */
    struct device_spec spec; /* the node, bus id or UUID it names */
    char source[160];        /* "SLURM_JOB_GPUS=2", "cgroup /sys/fs/cgroup/devices/..." */
    char why[640];           /* how the source maps to spec, or why nothing names a GPU */
};

/* Fills a. False with err when the environment names a GPU that nothing on
 * the box maps to a device (err names the variable and what is missing). */
bool device_allocated(device_env_fn env, void *ctx, const char *root, struct device_allocation *a,
                      char *err, size_t errlen);

#endif
