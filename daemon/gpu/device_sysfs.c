#define _POSIX_C_SOURCE 200809L
#include "daemon/gpu/device_sysfs.h"

#include <ctype.h>
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "daemon/gpu/device_names.h"

/* A small file whole (sysfs and procfs files are a page at most); false
 * when it cannot be read. */
static bool read_small(const char *path, char *buf, size_t cap)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return false;
    size_t n = fread(buf, 1, cap - 1, f);
    fclose(f);
    buf[n] = '\0';
    return true;
}

/* The value of "key: value" or "key=value" or "key value" lines, trimmed. */
static bool field(const char *text, const char *key, char sep, char *out, size_t cap)
{
    size_t klen = strlen(key);
    for (const char *p = text; p && *p; p = strchr(p, '\n'), p = p ? p + 1 : NULL) {
        if (strncmp(p, key, klen) != 0 || p[klen] != sep)
            continue;
        const char *v = p + klen + 1;
        while (*v == ' ' || *v == '\t')
            v++;
        size_t n = strcspn(v, "\n");
        while (n > 0 && (v[n - 1] == ' ' || v[n - 1] == '\t' || v[n - 1] == '\r'))
            n--;
        snprintf(out, cap, "%.*s", (int)n, v);
        return true;
    }
    return false;
}

static int compare_nvidia(const void *a, const void *b)
{
    return strcmp(((const struct sysfs_nvidia_gpu *)a)->bus_id,
                  ((const struct sysfs_nvidia_gpu *)b)->bus_id);
}

int sysfs_nvidia_gpus(const char *root, struct sysfs_nvidia_gpu *out, int max)
{
    char dir[1024];
    snprintf(dir, sizeof(dir), "%s/proc/driver/nvidia/gpus", root);
    DIR *d = opendir(dir);
    if (!d)
        return 0;
    int n = 0;
    struct dirent *e;
    while (n < max && (e = readdir(d))) {
        struct sysfs_nvidia_gpu g = {.minor = -1};
        if (!device_bus_id_normalize(e->d_name, g.bus_id, sizeof(g.bus_id)))
            continue;
        char path[1400], text[4096], v[128];
        snprintf(path, sizeof(path), "%s/%s/information", dir, e->d_name);
        if (!read_small(path, text, sizeof(text)))
            continue;
        if (field(text, "GPU UUID", ':', v, sizeof(v)))
            device_uuid_normalize(v, g.uuid, sizeof(g.uuid));
        if (field(text, "Device Minor", ':', v, sizeof(v)) && isdigit((unsigned char)v[0]))
            g.minor = atoi(v);
        field(text, "Model", ':', g.model, sizeof(g.model));
        out[n++] = g;
    }
    closedir(d);
    qsort(out, (size_t)n, sizeof(*out), compare_nvidia);
    return n;
}

static int compare_kfd(const void *a, const void *b)
{
    return ((const struct sysfs_kfd_gpu *)a)->node - ((const struct sysfs_kfd_gpu *)b)->node;
}

int sysfs_kfd_gpus(const char *root, struct sysfs_kfd_gpu *out, int max)
{
    char dir[1024];
    snprintf(dir, sizeof(dir), "%s/sys/class/kfd/kfd/topology/nodes", root);
    DIR *d = opendir(dir);
    if (!d)
        return 0;
    int n = 0;
    struct dirent *e;
    while (n < max && (e = readdir(d))) {
        if (!isdigit((unsigned char)e->d_name[0]))
            continue;
        char path[1400], text[8192], v[64];
        snprintf(path, sizeof(path), "%s/%s/gpu_id", dir, e->d_name);
        /* A CPU node's gpu_id is 0. */
        if (!read_small(path, v, sizeof(v)) || strtoull(v, NULL, 10) == 0)
            continue;
        snprintf(path, sizeof(path), "%s/%s/properties", dir, e->d_name);
        if (!read_small(path, text, sizeof(text)))
            continue;
        struct sysfs_kfd_gpu g = {.node = atoi(e->d_name), .render_minor = -1};
        if (field(text, "drm_render_minor", ' ', v, sizeof(v)))
            g.render_minor = atoi(v);
        if (field(text, "unique_id", ' ', v, sizeof(v)))
            g.unique_id = strtoull(v, NULL, 10);
        char dom[32];
        if (field(text, "location_id", ' ', v, sizeof(v))) {
            unsigned long loc = strtoul(v, NULL, 10);
            unsigned long domain = field(text, "domain", ' ', dom, sizeof(dom))
                                       ? strtoul(dom, NULL, 10) : 0;
            snprintf(g.bus_id, sizeof(g.bus_id), "%04lx:%02lx:%02lx.%lx", domain & 0xffff,
                     (loc >> 8) & 0xff, (loc >> 3) & 0x1f, loc & 7);
        }
        out[n++] = g;
    }
    closedir(d);
    qsort(out, (size_t)n, sizeof(*out), compare_kfd);
    return n;
}

static int compare_int(const void *a, const void *b)
{
    return *(const int *)a - *(const int *)b;
}

int sysfs_render_minors(const char *root, int *out, int max)
{
    char dir[1024];
    snprintf(dir, sizeof(dir), "%s/sys/class/drm", root);
    DIR *d = opendir(dir);
    if (!d)
        return 0;
    int n = 0;
    struct dirent *e;
    while (n < max && (e = readdir(d)))
        if (strncmp(e->d_name, "renderD", 7) == 0 && isdigit((unsigned char)e->d_name[7]))
            out[n++] = atoi(e->d_name + 7);
    closedir(d);
    qsort(out, (size_t)n, sizeof(int), compare_int);
    return n;
}

bool sysfs_drm_bus_id(const char *root, const char *node, char *bus, size_t cap)
{
    const char *base = strrchr(node, '/') ? strrchr(node, '/') + 1 : node;
    if (!*base || strchr(base, '.'))
        return false;
    char path[1200], text[4096], v[64];
    snprintf(path, sizeof(path), "%s/sys/class/drm/%s/device/uevent", root, base);
    if (read_small(path, text, sizeof(text)) && field(text, "PCI_SLOT_NAME", '=', v, sizeof(v)) &&
        device_bus_id_normalize(v, bus, cap))
        return true;
    /* Without a uevent file, the link itself: .../0000:01:00.0. */
    snprintf(path, sizeof(path), "%s/sys/class/drm/%s/device", root, base);
    char link[1024];
    ssize_t n = readlink(path, link, sizeof(link) - 1);
    if (n <= 0)
        return false;
    link[n] = '\0';
    const char *last = strrchr(link, '/') ? strrchr(link, '/') + 1 : link;
    return device_bus_id_normalize(last, bus, cap);
}

bool sysfs_bus_drm_nodes(const char *root, const char *bus, char *render, size_t rcap,
                         char *primary, size_t pcap)
{
    char dir[1200];
    snprintf(dir, sizeof(dir), "%s/sys/bus/pci/devices/%s/drm", root, bus);
    DIR *d = opendir(dir);
    if (!d)
        return false;
    bool any = false;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (strncmp(e->d_name, "renderD", 7) == 0 && isdigit((unsigned char)e->d_name[7])) {
            snprintf(render, rcap, "/dev/dri/%s", e->d_name);
            any = true;
        } else if (strncmp(e->d_name, "card", 4) == 0 && isdigit((unsigned char)e->d_name[4])) {
            snprintf(primary, pcap, "/dev/dri/%s", e->d_name);
            any = true;
        }
    }
    closedir(d);
    return any;
}
