#define _POSIX_C_SOURCE 200809L
#include "daemon/gpu/device_allocated.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "daemon/gpu/device_sysfs.h"

enum { MAX_GPUS = 64 };

/* What one source says: it names a GPU (a filled), it is wrong (err), or
 * the box has none of the devices it counts (note: look further). */
enum found { FOUND, FAILED, NOT_HERE };

/* Appends a sentence to the notes of sources that did not apply. */
static void add_note(char *notes, size_t cap, const char *fmt, const char *a, int i)
{
    size_t used = strlen(notes);
    if (used + 2 >= cap)
        return;
    if (used)
        used += (size_t)snprintf(notes + used, cap - used, "; ");
    snprintf(notes + used, cap - used, fmt, a, i);
}

static const char *value(device_env_fn env, void *ctx, const char *name)
{
    const char *v = env(name, ctx);
    return v && *v ? v : NULL;
}

/* The first of a comma-separated list, trimmed, and how many there are. */
static void first_entry(const char *list, char *out, size_t cap, int *count)
{
    *count = 1;
    for (const char *p = list; *p; p++)
        *count += *p == ',';
    while (*list == ' ')
        list++;
    size_t n = strcspn(list, ", ");
    snprintf(out, cap, "%.*s", (int)n, list);
}

static bool digits(const char *s)
{
    if (!*s)
        return false;
    for (; *s; s++)
        if (!isdigit((unsigned char)*s))
            return false;
    return true;
}

static void set_node(struct device_allocation *a, const char *node)
{
    a->named = true;
    a->spec.kind = DEVICE_SPEC_NODE;
    snprintf(a->spec.value, sizeof(a->spec.value), "%s", node);
    snprintf(a->spec.text, sizeof(a->spec.text), "%s", node);
}

static void set_named(struct device_allocation *a, enum device_spec_kind kind, const char *v)
{
    a->named = true;
    a->spec.kind = kind;
    snprintf(a->spec.value, sizeof(a->spec.value), "%s", v);
    snprintf(a->spec.text, sizeof(a->spec.text), "%s", v);
}

static const char *several(int count)
{
    return count > 1 ? " (the first of the task's GPUs: a daemon renders on one)" : "";
}

/* Slurm's global index i: /dev/nvidia<i>, else the i-th render node. */
static enum found slurm_index(struct device_allocation *a, const char *root, const char *name,
                              const char *v, char *notes, size_t ncap, char *err, size_t errlen)
{
    char first[32];
    int count;
    first_entry(v, first, sizeof(first), &count);
    if (!digits(first)) {
        snprintf(err, errlen, "%s=%.100s: expected GPU indices (0,1,...)", name, v);
        return FAILED;
    }
    int i = atoi(first);
    snprintf(a->source, sizeof(a->source), "%s=%.100s", name, v);
    struct sysfs_nvidia_gpu nv[MAX_GPUS];
    int n = sysfs_nvidia_gpus(root, nv, MAX_GPUS);
    if (n > 0) {
        for (int k = 0; k < n; k++)
            if (nv[k].minor == i) {
                char node[32];
                snprintf(node, sizeof(node), "/dev/nvidia%d", i);
                set_node(a, node);
                snprintf(a->why, sizeof(a->why),
                         "%s: Slurm's GPU %d is %s (gres.conf File=/dev/nvidia[...]), PCI %s in "
                         "NVIDIA's /proc/driver/nvidia%s", a->source, i, node, nv[k].bus_id,
                         several(count));
                return FOUND;
            }
        snprintf(err, errlen, "%s: NVIDIA's driver lists no GPU with device minor %d "
                 "(/proc/driver/nvidia/gpus has %d GPU(s)); name the GPU with --device", a->source,
                 i, n);
        return FAILED;
    }
    int minors[MAX_GPUS];
    int m = sysfs_render_minors(root, minors, MAX_GPUS);
    if (i < m) {
        char node[32];
        snprintf(node, sizeof(node), "/dev/dri/renderD%d", minors[i]);
        set_node(a, node);
        snprintf(a->why, sizeof(a->why),
                 "%s: Slurm's GPU %d is the node's DRM render node %d of %d in minor order, %s "
                 "(gres.conf File=/dev/dri/renderD[...])%s", a->source, i, i + 1, m, node,
                 several(count));
        return FOUND;
    }
    if (m == 0) {
        /* A node without GPUs (a test cluster's gres, File=/dev/null):
         * nothing to open but what EGL has. */
        add_note(notes, ncap, "%s names GPU %d, but the node has no GPU device to map it to (no "
                 "NVIDIA driver in /proc/driver/nvidia/gpus, no DRM render node in /sys/class/drm)",
                 a->source, i);
        return NOT_HERE;
    }
    snprintf(err, errlen, "%s: GPU %d, but the node has no NVIDIA driver "
             "(/proc/driver/nvidia/gpus) and %d DRM render node(s) (/sys/class/drm)", a->source,
             i, m);
    return FAILED;
}

/* An index into NVIDIA's GPUs in PCI bus order. */
static enum found nvidia_ordinal(struct device_allocation *a, device_env_fn env, void *ctx,
                                 const char *root, int k, int count, char *notes, size_t ncap,
                                 char *err, size_t errlen)
{
    struct sysfs_nvidia_gpu nv[MAX_GPUS];
    int n = sysfs_nvidia_gpus(root, nv, MAX_GPUS);
    if (n == 0) {
        add_note(notes, ncap, "%s names NVIDIA GPU %d, but NVIDIA's driver is not loaded (no "
                 "/proc/driver/nvidia/gpus)", a->source, k);
        return NOT_HERE;
    }
    if (k >= n) {
        snprintf(err, errlen, "%s: GPU %d, but NVIDIA's driver lists %d GPU(s) "
                 "(/proc/driver/nvidia/gpus)", a->source, k, n);
        return FAILED;
    }
    set_named(a, DEVICE_SPEC_BUS_ID, nv[k].bus_id);
    const char *order = value(env, ctx, "CUDA_DEVICE_ORDER");
    bool pci = order && strcmp(order, "PCI_BUS_ID") == 0;
    snprintf(a->why, sizeof(a->why), "%s: NVIDIA GPU %d in PCI bus order is %s%s%s", a->source,
             k, nv[k].bus_id,
             pci ? " (CUDA_DEVICE_ORDER=PCI_BUS_ID)"
                 : " (CUDA's default order, fastest first, is PCI bus order on a box of one GPU "
                   "model; set CUDA_DEVICE_ORDER=PCI_BUS_ID where models are mixed)",
             several(count));
    return FOUND;
}

static enum found cuda_visible(struct device_allocation *a, device_env_fn env, void *ctx,
                               const char *root, const char *v, char *notes, size_t ncap,
                               char *err, size_t errlen)
{
    char first[96], uuid[DEVICE_UUID_CAP];
    int count;
    first_entry(v, first, sizeof(first), &count);
    snprintf(a->source, sizeof(a->source), "CUDA_VISIBLE_DEVICES=%.100s", v);
    if (strncasecmp(first, "MIG-", 4) == 0) {
        snprintf(err, errlen, "%s: a MIG instance, which OpenGL cannot render on; give the "
                 "task a whole GPU", a->source);
        return FAILED;
    }
    if (device_uuid_normalize(first, uuid, sizeof(uuid))) {
        set_named(a, DEVICE_SPEC_UUID, uuid);
        snprintf(a->why, sizeof(a->why), "%s: the GPU with UUID %s%s", a->source, uuid,
                 several(count));
        return FOUND;
    }
    if (!digits(first)) {
        snprintf(err, errlen, "%s: expected GPU indices or UUIDs (GPU-...)", a->source);
        return FAILED;
    }
    return nvidia_ordinal(a, env, ctx, root, atoi(first), count, notes, ncap, err, errlen);
}

/* ROCR_VISIBLE_DEVICES or GPU_DEVICE_ORDINAL: ROCm's numbering. */
static enum found rocm_visible(struct device_allocation *a, device_env_fn env, void *ctx,
                               const char *root, const char *name, const char *v, char *notes,
                               size_t ncap, char *err, size_t errlen)
{
    char first[96];
    int count;
    first_entry(v, first, sizeof(first), &count);
    snprintf(a->source, sizeof(a->source), "%s=%.100s", name, v);
    struct sysfs_kfd_gpu kfd[MAX_GPUS];
    int n = sysfs_kfd_gpus(root, kfd, MAX_GPUS);
    char node[32];
    if (strncasecmp(first, "GPU-", 4) == 0 && strlen(first) == 20) {
        unsigned long long id = strtoull(first + 4, NULL, 16);
        for (int k = 0; k < n; k++)
            if (kfd[k].unique_id == id && kfd[k].render_minor >= 0) {
                snprintf(node, sizeof(node), "/dev/dri/renderD%d", kfd[k].render_minor);
                set_node(a, node);
                snprintf(a->why, sizeof(a->why), "%s: ROCm's GPU %s is KFD node %d, %s%s",
                         a->source, first, kfd[k].node, node, several(count));
                return FOUND;
            }
        snprintf(err, errlen, "%s: no KFD GPU node has the unique id %s "
                 "(/sys/class/kfd/kfd/topology has %d GPU(s))", a->source, first + 4, n);
        return FAILED;
    }
    if (!digits(first)) {
        snprintf(err, errlen, "%s: expected GPU indices or ROCm UUIDs (GPU-<16 hex digits>)",
                 a->source);
        return FAILED;
    }
    int k = atoi(first);
    if (n == 0 && strcmp(name, "GPU_DEVICE_ORDINAL") == 0)
        return nvidia_ordinal(a, env, ctx, root, k, count, notes, ncap, err, errlen);
    if (n == 0) {
        add_note(notes, ncap, "%s names ROCm GPU %d, but there is no KFD topology "
                 "(/sys/class/kfd/kfd/topology)", a->source, k);
        return NOT_HERE;
    }
    if (k < n && kfd[k].render_minor >= 0) {
        snprintf(node, sizeof(node), "/dev/dri/renderD%d", kfd[k].render_minor);
        set_node(a, node);
        snprintf(a->why, sizeof(a->why), "%s: ROCm's GPU %d is KFD node %d, %s%s", a->source, k,
                 kfd[k].node, node, several(count));
        return FOUND;
    }
    snprintf(err, errlen, "%s: GPU %d, but the KFD topology (/sys/class/kfd/kfd/topology) has %d "
             "GPU node(s) with a render node", a->source, k, n);
    return FAILED;
}

/* The device cgroup (v1): the GPU device files its devices.list allows,
 * when it does not allow every device. False (and nothing named) when
 * there is no such list or it restricts nothing. */
static bool cgroup_device(struct device_allocation *a, const char *root, char *note, size_t cap)
{
    char path[1200], text[4096];
    snprintf(path, sizeof(path), "%s/proc/self/cgroup", root);
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(note, cap, "no /proc/self/cgroup");
        return false;
    }
    char line[1024], group[900] = "";
    bool found = false;
    while (!found && fgets(line, sizeof(line), f)) {
        /* "4:devices:/slurm/uid_1000/job_42/step_0/task_0" */
        char *c1 = strchr(line, ':'), *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
        if (!c2 || (size_t)(c2 - c1 - 1) != 7 || strncmp(c1 + 1, "devices", 7) != 0)
            continue;
        c2[1 + strcspn(c2 + 1, "\n")] = '\0';
        snprintf(group, sizeof(group), "%s", c2 + 1);
        found = true;
    }
    fclose(f);
    if (!found) {
        snprintf(note, cap, "no cgroup v1 device controller (under cgroup v2 the device rules are "
                 "an eBPF program that cannot be read)");
        return false;
    }
    snprintf(path, sizeof(path), "%s/sys/fs/cgroup/devices%s/devices.list", root,
             strcmp(group, "/") == 0 ? "" : group);
    f = fopen(path, "r");
    if (!f) {
        snprintf(note, cap, "the device cgroup's devices.list is unreadable");
        return false;
    }
    int nvidia = -1, render = -1, card = -1;
    bool everything = false;
    while (fgets(text, sizeof(text), f)) {
        char type;
        char maj[16], min[16];
        if (sscanf(text, "%c %15[^:]:%15s", &type, maj, min) != 3)
            continue;
        if (type == 'a') {
            everything = true;
            continue;
        }
        if (type != 'c' || !digits(maj) || !digits(min))
            continue;
        int M = atoi(maj), m = atoi(min);
        /* NVIDIA's GPUs are 195:N (255 is nvidiactl, 254 nvidia-modeset);
         * DRM's are 226:N, render nodes from 128. */
        if (M == 195 && m < 254 && nvidia < 0)
            nvidia = m;
        else if (M == 226 && m >= 128 && render < 0)
            render = m;
        else if (M == 226 && m < 64 && card < 0)
            card = m;
    }
    fclose(f);
    if (everything || (nvidia < 0 && render < 0 && card < 0)) {
        snprintf(note, cap, "the device cgroup %s allows %s", group,
                 everything ? "every device" : "no GPU device file");
        return false;
    }
    char node[32];
    if (nvidia >= 0)
        snprintf(node, sizeof(node), "/dev/nvidia%d", nvidia);
    else if (render >= 0)
        snprintf(node, sizeof(node), "/dev/dri/renderD%d", render);
    else
        snprintf(node, sizeof(node), "/dev/dri/card%d", card);
    set_node(a, node);
    snprintf(a->source, sizeof(a->source), "device cgroup %.140s", group);
    snprintf(a->why, sizeof(a->why), "the device cgroup %.400s allows %s (the first GPU device "
             "file its devices.list names)", group, node);
    return true;
}

bool device_allocated(device_env_fn env, void *ctx, const char *root, struct device_allocation *a,
                      char *err, size_t errlen)
{
    memset(a, 0, sizeof(*a));
    a->spec.kind = DEVICE_SPEC_AUTO;
    char notes[400] = "";
    enum found f = NOT_HERE;
    static const char *const slurm[] = {"SLURM_STEP_GPUS", "SLURM_JOB_GPUS"};
    const char *v = NULL;
    /* The step's GPUs are the job's for this step: the first set wins. */
    for (int i = 0; i < 2 && !v; i++)
        if ((v = value(env, ctx, slurm[i])))
            f = slurm_index(a, root, slurm[i], v, notes, sizeof(notes), err, errlen);
    /* Slurm writes NoDevFiles when the GPUs' gres has no File=. */
    if (f == NOT_HERE && (v = value(env, ctx, "CUDA_VISIBLE_DEVICES")) &&
        strcmp(v, "NoDevFiles") != 0)
        f = cuda_visible(a, env, ctx, root, v, notes, sizeof(notes), err, errlen);
    static const char *const rocm[] = {"ROCR_VISIBLE_DEVICES", "GPU_DEVICE_ORDINAL"};
    for (int i = 0; i < 2 && f == NOT_HERE; i++)
        if ((v = value(env, ctx, rocm[i])) && strcmp(v, "NoDevFiles") != 0)
            f = rocm_visible(a, env, ctx, root, rocm[i], v, notes, sizeof(notes), err, errlen);
    if (f == FAILED)
        return false;
    if (f == FOUND)
        return true;
    char cgroup[300] = "";
    if (cgroup_device(a, root, cgroup, sizeof(cgroup)))
        return true;
    memset(&a->spec, 0, sizeof(a->spec));
    a->spec.kind = DEVICE_SPEC_AUTO;
    snprintf(a->source, sizeof(a->source), "nothing");
    snprintf(a->why, sizeof(a->why), "no GPU this box has is named by the scheduler (%s%s%s): the "
             "default choice", notes[0] ? notes : "SLURM_STEP_GPUS, SLURM_JOB_GPUS, "
             "CUDA_VISIBLE_DEVICES, ROCR_VISIBLE_DEVICES and GPU_DEVICE_ORDINAL unset",
             "; ", cgroup);
    return true;
}
