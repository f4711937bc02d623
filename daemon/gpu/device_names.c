#define _POSIX_C_SOURCE 200809L
#include "daemon/gpu/device_names.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "daemon/gpu/device_sysfs.h"

static bool is_hex(char c) { return isxdigit((unsigned char)c) != 0; }

/* Parses n hex digits at s into v; false unless exactly those are hex. */
static bool hex_field(const char *s, size_t n, unsigned long *v)
{
    if (n == 0 || n > 8)
        return false;
    *v = 0;
    for (size_t i = 0; i < n; i++) {
        if (!is_hex(s[i]))
            return false;
        *v = *v * 16 + (unsigned long)(isdigit((unsigned char)s[i]) ? s[i] - '0'
                                                                    : tolower((unsigned char)s[i]) - 'a' + 10);
    }
    return true;
}

bool device_bus_id_normalize(const char *text, char *out, size_t cap)
{
    if (strncasecmp(text, "pci:", 4) == 0)
        text += 4;
    /* [domain:]bus:device.function, hex. */
    const char *dot = strrchr(text, '.');
    if (!dot)
        return false;
    const char *colon[2];
    int ncolons = 0;
    for (const char *q = text; q < dot; q++)
        if (*q == ':') {
            if (ncolons == 2)
                return false;
            colon[ncolons++] = q;
        }
    if (ncolons == 0)
        return false;
    unsigned long domain = 0, bus, dev, fn;
    const char *bus_at = text, *dev_colon = colon[ncolons - 1];
    if (ncolons == 2) {
        if (!hex_field(text, (size_t)(colon[0] - text), &domain) || domain > 0xffff)
            return false;
        bus_at = colon[0] + 1;
    }
    if (!hex_field(bus_at, (size_t)(dev_colon - bus_at), &bus) ||
        !hex_field(dev_colon + 1, (size_t)(dot - dev_colon - 1), &dev) ||
        !hex_field(dot + 1, strlen(dot + 1), &fn) || bus > 0xff || dev > 0x1f || fn > 7)
        return false;
    snprintf(out, cap, "%04lx:%02lx:%02lx.%lx", domain, bus, dev, fn);
    return true;
}

bool device_uuid_normalize(const char *text, char *out, size_t cap)
{
    if (strncasecmp(text, "uuid:", 5) == 0)
        text += 5;
    if (strncasecmp(text, "GPU-", 4) == 0)
        text += 4;
    unsigned char bytes[16];
    int digits = 0;
    for (const char *p = text; *p; p++) {
        if (*p == '-')
            continue;
        unsigned long v;
        if (digits >= 32 || !hex_field(p, 1, &v))
            return false;
        if (digits % 2 == 0)
            bytes[digits / 2] = (unsigned char)(v << 4);
        else
            bytes[digits / 2] |= (unsigned char)v;
        digits++;
    }
    if (digits != 32)
        return false;
    device_uuid_from_bytes(bytes, out, cap);
    return true;
}

void device_uuid_from_bytes(const unsigned char b[16], char *out, size_t cap)
{
    snprintf(out, cap,
             "%02x%02x%02x%02x-%02x%02x-%02x%02x-%02x%02x-%02x%02x%02x%02x%02x%02x", b[0], b[1],
             b[2], b[3], b[4], b[5], b[6], b[7], b[8], b[9], b[10], b[11], b[12], b[13], b[14],
             b[15]);
}

void device_names_init(struct gpu_device_names *d, int index)
{
    memset(d, 0, sizeof(*d));
    d->index = index;
    d->cuda_device = -1;
    d->nvidia_minor = -1;
}

void device_names_from_sysfs(struct gpu_device_names *d, const char *root)
{
    const char *node = d->render_node[0] ? d->render_node : d->drm_node;
    if (!d->bus_id[0] && node[0] && sysfs_drm_bus_id(root, node, d->bus_id, sizeof(d->bus_id)))
        snprintf(d->bus_id_from, sizeof(d->bus_id_from), "sysfs (/sys/class/drm)");
    struct sysfs_nvidia_gpu gpus[16];
    int n = sysfs_nvidia_gpus(root, gpus, 16);
    for (int i = 0; i < n; i++) {
        if (!d->bus_id[0] && d->uuid[0] && strcmp(gpus[i].uuid, d->uuid) == 0) {
            snprintf(d->bus_id, sizeof(d->bus_id), "%s", gpus[i].bus_id);
            snprintf(d->bus_id_from, sizeof(d->bus_id_from), "NVIDIA's /proc/driver/nvidia");
        }
        if (!d->bus_id[0] || strcmp(gpus[i].bus_id, d->bus_id) != 0)
            continue;
        d->nvidia_minor = gpus[i].minor;
        if (!d->uuid[0] && gpus[i].uuid[0]) {
            snprintf(d->uuid, sizeof(d->uuid), "%s", gpus[i].uuid);
            snprintf(d->uuid_from, sizeof(d->uuid_from), "NVIDIA's /proc/driver/nvidia");
        }
    }
    if (d->bus_id[0] && !d->render_node[0]) {
        char render[DEVICE_NODE_CAP] = "", primary[DEVICE_NODE_CAP] = "";
        if (sysfs_bus_drm_nodes(root, d->bus_id, render, sizeof(render), primary,
                                sizeof(primary))) {
            snprintf(d->render_node, sizeof(d->render_node), "%s", render);
            if (!d->drm_node[0])
                snprintf(d->drm_node, sizeof(d->drm_node), "%s", primary);
        }
    }
}

static bool all_digits(const char *s)
{
    if (!*s)
        return false;
    for (; *s; s++)
        if (!isdigit((unsigned char)*s))
            return false;
    return true;
}

/* "renderD128", "card0" or "nvidia0" and nothing else. */
static bool node_name(const char *s)
{
    if (strncmp(s, "renderD", 7) == 0)
        return all_digits(s + 7);
    if (strncmp(s, "nvidia", 6) == 0)
        return all_digits(s + 6);
    return strncmp(s, "card", 4) == 0 && all_digits(s + 4);
}

bool device_spec_parse(const char *text, struct device_spec *spec, char *err, size_t errlen)
{
    memset(spec, 0, sizeof(*spec));
    snprintf(spec->text, sizeof(spec->text), "%s", text);
    if (!*text || strcmp(text, "auto") == 0) {
        spec->kind = DEVICE_SPEC_AUTO;
        return true;
    }
    if (strcmp(text, "allocated") == 0) {
        spec->kind = DEVICE_SPEC_ALLOCATED;
        return true;
    }
    if (all_digits(text) && strlen(text) <= 3) {
        spec->kind = DEVICE_SPEC_INDEX;
        spec->index = atoi(text);
        return true;
    }
    if (strncmp(text, "/dev/", 5) == 0 || node_name(text)) {
        const char *base = strrchr(text, '/') ? strrchr(text, '/') + 1 : text;
        if (node_name(base) && strlen(text) < sizeof(spec->value)) {
            spec->kind = DEVICE_SPEC_NODE;
            if (text[0] == '/')
                snprintf(spec->value, sizeof(spec->value), "%s", text);
            else
                snprintf(spec->value, sizeof(spec->value), "/dev/%s%s",
                         strncmp(base, "nvidia", 6) == 0 ? "" : "dri/", base);
            return true;
        }
    } else if (device_bus_id_normalize(text, spec->value, sizeof(spec->value))) {
        spec->kind = DEVICE_SPEC_BUS_ID;
        return true;
    } else if (device_uuid_normalize(text, spec->value, sizeof(spec->value))) {
        spec->kind = DEVICE_SPEC_UUID;
        return true;
    }
    snprintf(err, errlen,
             "\"%.100s\" names no device: give an EGL index (0), a DRM node "
             "(/dev/dri/renderD128, renderD128, card1) or NVIDIA's device file (/dev/nvidia1), "
             "a PCI bus id (0000:41:00.0), a "
             "UUID (GPU-8c5f... or 32 hex digits), auto (the first hardware device) or "
             "allocated (the GPU the batch scheduler gave: SLURM_STEP_GPUS, SLURM_JOB_GPUS, "
             "CUDA_VISIBLE_DEVICES, ROCR_VISIBLE_DEVICES, GPU_DEVICE_ORDINAL or the device "
             "cgroup)", text);
    return false;
}

const char *device_spec_kind_name(enum device_spec_kind kind)
{
    switch (kind) {
    case DEVICE_SPEC_AUTO: return "auto";
    case DEVICE_SPEC_INDEX: return "index";
    case DEVICE_SPEC_NODE: return "node";
    case DEVICE_SPEC_BUS_ID: return "bus_id";
    case DEVICE_SPEC_UUID: return "uuid";
    case DEVICE_SPEC_ALLOCATED: return "allocated";
    }
    return "?";
}

static bool matches(const struct device_spec *s, const struct gpu_device_names *d)
{
    switch (s->kind) {
    case DEVICE_SPEC_INDEX: return d->index == s->index;
    case DEVICE_SPEC_NODE: {
        const char *base = strrchr(s->value, '/') ? strrchr(s->value, '/') + 1 : s->value;
        if (strncmp(base, "nvidia", 6) == 0)
            return d->nvidia_minor >= 0 && d->nvidia_minor == atoi(base + 6);
        return (d->render_node[0] && strcmp(d->render_node, s->value) == 0) ||
               (d->drm_node[0] && strcmp(d->drm_node, s->value) == 0);
    }
    case DEVICE_SPEC_BUS_ID: return d->bus_id[0] && strcmp(d->bus_id, s->value) == 0;
    case DEVICE_SPEC_UUID: return d->uuid[0] && strcmp(d->uuid, s->value) == 0;
    default: return false;
    }
}

void device_names_line(const struct gpu_device_names *d, char *out, size_t cap)
{
    const char *node = d->render_node[0] ? d->render_node : d->drm_node;
    snprintf(out, cap, "%d: %s%s%s%s, node %s, bus id %s, uuid %s", d->index,
             d->renderer[0] ? d->renderer : "(renderer not known before a context)",
             d->vendor[0] ? " by " : "", d->vendor, d->software ? " [software]" : "",
             node[0] ? node : "-", d->bus_id[0] ? d->bus_id : "-", d->uuid[0] ? d->uuid : "-");
}

int device_spec_match(const struct device_spec *spec, const struct gpu_device_names *devs, int n,
                      char *err, size_t errlen)
{
    for (int i = 0; i < n; i++)
        if (matches(spec, &devs[i]))
            return i;
    static const char *const what[] = {
        [DEVICE_SPEC_INDEX] = "the index", [DEVICE_SPEC_NODE] = "the device node",
        [DEVICE_SPEC_BUS_ID] = "the PCI bus id", [DEVICE_SPEC_UUID] = "the UUID"};
    const char *asked = spec->kind == DEVICE_SPEC_INDEX ? spec->text : spec->value;
    size_t used = (size_t)snprintf(err, errlen, "no EGL device has %s %s; %d EGL device(s): ",
                                   spec->kind <= DEVICE_SPEC_UUID && what[spec->kind]
                                       ? what[spec->kind] : "the name",
                                   asked, n);
    for (int i = 0; i < n && used < errlen; i++) {
        char line[400];
        device_names_line(&devs[i], line, sizeof(line));
        used += (size_t)snprintf(err + used, errlen - used, "%s%s", i ? "; " : "", line);
    }
    if (n == 0 && used < errlen)
        snprintf(err + used, errlen - used, "none (no EGL_EXT_device_enumeration?)");
    return -1;
}

static json_t *str_or_null(const char *s) { return s[0] ? json_string(s) : json_null(); }

json_t *device_names_json(const struct gpu_device_names *d)
{
    json_t *j = json_pack("{s:i, s:b}", "index", d->index, "software", d->software);
    json_object_set_new(j, "vendor", str_or_null(d->vendor));
    json_object_set_new(j, "renderer", str_or_null(d->renderer));
    json_object_set_new(j, "driver", str_or_null(d->driver));
    json_object_set_new(j, "drm_node", str_or_null(d->drm_node));
    json_object_set_new(j, "render_node", str_or_null(d->render_node));
    json_object_set_new(j, "bus_id", str_or_null(d->bus_id));
    if (d->bus_id[0])
        json_object_set_new(j, "bus_id_from", str_or_null(d->bus_id_from));
    json_object_set_new(j, "uuid", str_or_null(d->uuid));
    if (d->uuid[0])
        json_object_set_new(j, "uuid_from", str_or_null(d->uuid_from));
    json_object_set_new(j, "cuda_device", d->cuda_device >= 0 ? json_integer(d->cuda_device)
                                                              : json_null());
    json_object_set_new(j, "nvidia_minor", d->nvidia_minor >= 0 ? json_integer(d->nvidia_minor)
                                                                : json_null());
    return j;
}
