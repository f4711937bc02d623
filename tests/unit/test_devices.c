/* Naming and picking the GPU, GL-free, over fake sysfs and procfs trees: a
 * --device setting's forms, the names sysfs and NVIDIA's procfs add to an
 * EGL device, matching and its error, and --device allocated from Slurm's,
 * CUDA's and ROCm's variables and the device cgroup. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "daemon/gpu/device_allocated.h"
#include "daemon/gpu/device_names.h"
#include "daemon/gpu/device_sysfs.h"
#include "tests/unit/check.h"

static char root_a[64], root_b[64], root_c[64];

/* Writes text to root/path, making its folders. */
static void put(const char *root, const char *path, const char *text)
{
    char full[512];
    snprintf(full, sizeof(full), "%s/%s", root, path);
    for (char *p = full + strlen(root) + 1; *p; p++)
        if (*p == '/') {
            *p = '\0';
            mkdir(full, 0755);
            *p = '/';
        }
    if (text) {
        FILE *f = fopen(full, "w");
        fputs(text, f);
        fclose(f);
    } else {
        mkdir(full, 0755);
    }
}

#define UUID0 "8c5f3b1e-5d2a-4c6f-9b7e-1a2b3c4d5e6f"
#define UUID1 "0a0b0c0d-1111-2222-3333-444455556666"

/* An NVIDIA box of two GPUs, with nvidia-drm's nodes. */
static void make_nvidia_box(const char *r)
{
    put(r, "proc/driver/nvidia/gpus/0000:41:00.0/information",
        "Model: \t\t NVIDIA H100 80GB HBM3\nIRQ:   \t\t 123\nGPU UUID: \t GPU-" UUID0 "\n"
        "Bus Location: \t 0000:41:00.0\nDevice Minor: \t 0\nGPU Excluded:\t No\n");
    put(r, "proc/driver/nvidia/gpus/0000:81:00.0/information",
        "Model: \t\t NVIDIA H100 80GB HBM3\nGPU UUID: \t GPU-" UUID1 "\n"
        "Bus Location: \t 0000:81:00.0\nDevice Minor: \t 1\n");
    put(r, "sys/class/drm/card1/device/uevent", "DRIVER=nvidia\nPCI_SLOT_NAME=0000:41:00.0\n");
    put(r, "sys/class/drm/renderD128/device/uevent", "DRIVER=nvidia\nPCI_SLOT_NAME=0000:41:00.0\n");
    put(r, "sys/class/drm/card2/device/uevent", "PCI_SLOT_NAME=0000:81:00.0\n");
    put(r, "sys/class/drm/renderD129/device/uevent", "PCI_SLOT_NAME=0000:81:00.0\n");
    put(r, "sys/bus/pci/devices/0000:41:00.0/drm/card1", NULL);
    put(r, "sys/bus/pci/devices/0000:41:00.0/drm/renderD128", NULL);
    put(r, "sys/bus/pci/devices/0000:81:00.0/drm/card2", NULL);
    put(r, "sys/bus/pci/devices/0000:81:00.0/drm/renderD129", NULL);
    put(r, "proc/self/cgroup", "12:memory:/slurm/job_7\n5:devices:/slurm/job_7/step_0\n");
    put(r, "sys/fs/cgroup/devices/slurm/job_7/step_0/devices.list",
        "c 195:255 rwm\nc 195:254 rwm\nc 195:1 rwm\nc 1:3 rwm\n");
}

/* An AMD box: a CPU node and two GPU nodes, numbered by ROCm in node order
 * but with their render nodes the other way round. */
static void make_amd_box(const char *r)
{
    put(r, "sys/class/kfd/kfd/topology/nodes/0/gpu_id", "0\n");
    put(r, "sys/class/kfd/kfd/topology/nodes/0/properties", "cpu_cores_count 64\nsimd_count 0\n");
    put(r, "sys/class/kfd/kfd/topology/nodes/1/gpu_id", "53211\n");
    /* location_id 0xc100 = bus 0xc1, device 0, function 0. */
    put(r, "sys/class/kfd/kfd/topology/nodes/1/properties",
        "simd_count 416\ndrm_render_minor 129\nlocation_id 49408\ndomain 0\n"
        "unique_id 1311768467463790320\n");
    put(r, "sys/class/kfd/kfd/topology/nodes/2/gpu_id", "61024\n");
    put(r, "sys/class/kfd/kfd/topology/nodes/2/properties",
        "simd_count 416\ndrm_render_minor 128\nlocation_id 8448\ndomain 0\nunique_id 42\n");
    put(r, "sys/class/drm/renderD128/device/uevent", "PCI_SLOT_NAME=0000:21:00.0\n");
    put(r, "sys/class/drm/renderD129/device/uevent", "PCI_SLOT_NAME=0000:c1:00.0\n");
    put(r, "proc/self/cgroup", "0::/user.slice\n");
}

struct env {
    const char *pairs[16][2];
};

static const char *env_get(const char *name, void *ctx)
{
    struct env *e = ctx;
    for (int i = 0; i < 16 && e->pairs[i][0]; i++)
        if (strcmp(e->pairs[i][0], name) == 0)
            return e->pairs[i][1];
    return NULL;
}

static void test_normalize(void)
{
    char out[64];
    CHECK(device_bus_id_normalize("0000:41:00.0", out, sizeof(out)) && !strcmp(out, "0000:41:00.0"));
    CHECK(device_bus_id_normalize("00000000:41:00.0", out, sizeof(out)) &&
          !strcmp(out, "0000:41:00.0")); /* nvidia-smi's 8-digit domain */
    CHECK(device_bus_id_normalize("C1:00.0", out, sizeof(out)) && !strcmp(out, "0000:c1:00.0"));
    CHECK(device_bus_id_normalize("pci:0001:41:1f.7", out, sizeof(out)) &&
          !strcmp(out, "0001:41:1f.7"));
    CHECK(!device_bus_id_normalize("41:00", out, sizeof(out)));
    CHECK(!device_bus_id_normalize("0000:41:20.0", out, sizeof(out))); /* device > 0x1f */
    CHECK(!device_bus_id_normalize("zz:00.0", out, sizeof(out)));
    CHECK(!device_bus_id_normalize("1:2:3:00.0", out, sizeof(out)));
    CHECK(device_uuid_normalize("GPU-" UUID0, out, sizeof(out)) && !strcmp(out, UUID0));
    CHECK(device_uuid_normalize("uuid:8C5F3B1E5D2A4C6F9B7E1A2B3C4D5E6F", out, sizeof(out)) &&
          !strcmp(out, UUID0));
    CHECK(!device_uuid_normalize("GPU-8c5f3b1e", out, sizeof(out)));
    CHECK(!device_uuid_normalize("GPU-" UUID0 "00", out, sizeof(out)));
}

static void test_parse(void)
{
    struct device_spec s;
    char err[1024];
    CHECK(device_spec_parse("1", &s, err, sizeof(err)) && s.kind == DEVICE_SPEC_INDEX &&
          s.index == 1);
    CHECK(device_spec_parse("auto", &s, err, sizeof(err)) && s.kind == DEVICE_SPEC_AUTO);
    CHECK(device_spec_parse("allocated", &s, err, sizeof(err)) && s.kind == DEVICE_SPEC_ALLOCATED);
    CHECK(device_spec_parse("/dev/dri/renderD129", &s, err, sizeof(err)) &&
          s.kind == DEVICE_SPEC_NODE && !strcmp(s.value, "/dev/dri/renderD129"));
    CHECK(device_spec_parse("renderD129", &s, err, sizeof(err)) && s.kind == DEVICE_SPEC_NODE &&
          !strcmp(s.value, "/dev/dri/renderD129"));
    CHECK(device_spec_parse("card2", &s, err, sizeof(err)) && !strcmp(s.value, "/dev/dri/card2"));
    CHECK(device_spec_parse("nvidia1", &s, err, sizeof(err)) && !strcmp(s.value, "/dev/nvidia1"));
    CHECK(device_spec_parse("81:00.0", &s, err, sizeof(err)) && s.kind == DEVICE_SPEC_BUS_ID &&
          !strcmp(s.value, "0000:81:00.0"));
    CHECK(device_spec_parse("GPU-" UUID1, &s, err, sizeof(err)) && s.kind == DEVICE_SPEC_UUID &&
          !strcmp(s.value, UUID1));
    err[0] = '\0';
    CHECK(!device_spec_parse("llvmpipe", &s, err, sizeof(err)) &&
          strstr(err, "\"llvmpipe\" names no device") && strstr(err, "/dev/dri/renderD128") &&
          strstr(err, "allocated"));
    CHECK(!device_spec_parse("/dev/sda", &s, err, sizeof(err)));
    CHECK(strcmp(device_spec_kind_name(DEVICE_SPEC_BUS_ID), "bus_id") == 0);
}

/* EGL's view of the NVIDIA box: device 0 llvmpipe, 1 the GPU EGL names by
 * its UUID alone, 2 the one it names by its render node. */
static int nvidia_devices(struct gpu_device_names *d)
{
    device_names_init(&d[0], 0);
    d[0].software = true;
    snprintf(d[0].renderer, sizeof(d[0].renderer), "llvmpipe (LLVM 15.0.6, 256 bits)");
    device_names_init(&d[1], 1);
    snprintf(d[1].uuid, sizeof(d[1].uuid), UUID0);
    snprintf(d[1].uuid_from, sizeof(d[1].uuid_from), "EGL_EXT_device_persistent_id");
    device_names_init(&d[2], 2);
    snprintf(d[2].drm_node, sizeof(d[2].drm_node), "/dev/dri/card2");
    snprintf(d[2].render_node, sizeof(d[2].render_node), "/dev/dri/renderD129");
    for (int i = 0; i < 3; i++)
        device_names_from_sysfs(&d[i], root_a);
    return 3;
}

static int pick(const char *text, const struct gpu_device_names *d, int n, char *err, size_t cap)
{
    struct device_spec s;
    if (!device_spec_parse(text, &s, err, cap))
        return -2;
    return device_spec_match(&s, d, n, err, cap);
}

static void test_names_and_match(void)
{
    struct gpu_device_names d[3];
    int n = nvidia_devices(d);
    /* llvmpipe: a name but no node, bus id or UUID. */
    CHECK(!d[0].bus_id[0] && !d[0].uuid[0] && d[0].nvidia_minor == -1);
    /* The UUID gives the bus id (NVIDIA's procfs), the bus id the nodes. */
    CHECK(!strcmp(d[1].bus_id, "0000:41:00.0") && strstr(d[1].bus_id_from, "nvidia"));
    CHECK(!strcmp(d[1].render_node, "/dev/dri/renderD128") && !strcmp(d[1].drm_node, "/dev/dri/card1"));
    CHECK(d[1].nvidia_minor == 0 && !strcmp(d[1].uuid_from, "EGL_EXT_device_persistent_id"));
    /* The node gives the bus id (sysfs), the bus id the UUID and minor. */
    CHECK(!strcmp(d[2].bus_id, "0000:81:00.0") && strstr(d[2].bus_id_from, "sysfs"));
    CHECK(!strcmp(d[2].uuid, UUID1) && d[2].nvidia_minor == 1);
    char err[2048];
    CHECK(pick("2", d, n, err, sizeof(err)) == 2);
    CHECK(pick("/dev/dri/renderD128", d, n, err, sizeof(err)) == 1);
    CHECK(pick("card2", d, n, err, sizeof(err)) == 2);
    CHECK(pick("/dev/nvidia1", d, n, err, sizeof(err)) == 2);
    CHECK(pick("0000:41:00.0", d, n, err, sizeof(err)) == 1);
    CHECK(pick("00000000:81:00.0", d, n, err, sizeof(err)) == 2);
    CHECK(pick("GPU-" UUID1, d, n, err, sizeof(err)) == 2);
    CHECK(pick(UUID0, d, n, err, sizeof(err)) == 1);
    /* A name that matches nothing lists every device with its names. */
    CHECK(pick("/dev/dri/renderD130", d, n, err, sizeof(err)) == -1);
    CHECK(strstr(err, "no EGL device has the device node /dev/dri/renderD130") &&
          strstr(err, "3 EGL device(s)") && strstr(err, "0: llvmpipe (LLVM 15.0.6, 256 bits) [software], node -, bus id -") &&
          strstr(err, "bus id 0000:81:00.0") && strstr(err, UUID0));
    CHECK(pick("7", d, n, err, sizeof(err)) == -1 && strstr(err, "no EGL device has the index 7"));
    CHECK(pick("c1:00.0", d, 1, err, sizeof(err)) == -1 &&
          strstr(err, "the PCI bus id 0000:c1:00.0") && strstr(err, "1 EGL device(s)"));
    json_t *j = device_names_json(&d[0]);
    CHECK(json_is_null(json_object_get(j, "bus_id")) && json_is_null(json_object_get(j, "uuid")) &&
          json_is_null(json_object_get(j, "render_node")) &&
          json_is_true(json_object_get(j, "software")) && !json_object_get(j, "bus_id_from"));
    json_decref(j);
    j = device_names_json(&d[2]);
    CHECK(!strcmp(json_string_value(json_object_get(j, "bus_id")), "0000:81:00.0") &&
          json_integer_value(json_object_get(j, "nvidia_minor")) == 1);
    json_decref(j);
}

/* --device allocated on root with env: the device of devs it picks, or -1
 * (nothing named: *why says so), or -2 (an error, in why). */
static int allocated(const char *root, struct env *env, const struct gpu_device_names *devs,
                     int n, char *why, size_t cap)
{
    struct device_allocation a;
    if (!device_allocated(env_get, env, root, &a, why, cap))
        return -2;
    snprintf(why, cap, "%s", a.why);
    if (!a.named)
        return -1;
    char err[2048];
    int i = device_spec_match(&a.spec, devs, n, err, sizeof(err));
    if (i < 0)
        snprintf(why, cap, "%s", err);
    return i;
}

static void test_allocated_nvidia(void)
{
    struct gpu_device_names d[3];
    int n = nvidia_devices(d);
    char why[2048];
    /* Slurm's global index is /dev/nvidiaN, whatever EGL's order. */
    struct env e1 = {{{"SLURM_JOB_GPUS", "1"}, {"CUDA_VISIBLE_DEVICES", "0"}}};
    CHECK(allocated(root_a, &e1, d, n, why, sizeof(why)) == 2);
    CHECK(strstr(why, "SLURM_JOB_GPUS=1") && strstr(why, "/dev/nvidia1") &&
          strstr(why, "0000:81:00.0"));
    struct env e2 = {{{"SLURM_JOB_GPUS", "0,1"}, {"SLURM_STEP_GPUS", "0"}}};
    CHECK(allocated(root_a, &e2, d, n, why, sizeof(why)) == 1 && strstr(why, "SLURM_STEP_GPUS=0"));
    struct env e3 = {{{"SLURM_JOB_GPUS", "0,1"}}};
    CHECK(allocated(root_a, &e3, d, n, why, sizeof(why)) == 1 && strstr(why, "the first of"));
    struct env e4 = {{{"SLURM_JOB_GPUS", "5"}}};
    CHECK(allocated(root_a, &e4, d, n, why, sizeof(why)) == -2 &&
          strstr(why, "no GPU with device minor 5"));
    struct env e5 = {{{"SLURM_JOB_GPUS", "gpu0"}}};
    CHECK(allocated(root_a, &e5, d, n, why, sizeof(why)) == -2 && strstr(why, "expected GPU indices"));
    /* CUDA: a UUID, or an index in PCI bus order. */
    struct env e6 = {{{"CUDA_VISIBLE_DEVICES", "GPU-" UUID1 ",GPU-" UUID0}}};
    CHECK(allocated(root_a, &e6, d, n, why, sizeof(why)) == 2);
    struct env e7 = {{{"CUDA_VISIBLE_DEVICES", "1"}}};
    CHECK(allocated(root_a, &e7, d, n, why, sizeof(why)) == 2 &&
          strstr(why, "PCI bus order is 0000:81:00.0") && strstr(why, "CUDA_DEVICE_ORDER"));
    struct env e8 = {{{"CUDA_VISIBLE_DEVICES", "MIG-GPU-" UUID0 "/1/0"}}};
    CHECK(allocated(root_a, &e8, d, n, why, sizeof(why)) == -2 && strstr(why, "MIG"));
    struct env e9 = {{{"CUDA_VISIBLE_DEVICES", "2"}}};
    CHECK(allocated(root_a, &e9, d, n, why, sizeof(why)) == -2 && strstr(why, "lists 2 GPU(s)"));
    /* GPU_DEVICE_ORDINAL without KFD: NVIDIA's order. */
    struct env e10 = {{{"GPU_DEVICE_ORDINAL", "0"}}};
    CHECK(allocated(root_a, &e10, d, n, why, sizeof(why)) == 1);
    /* Nothing set: the device cgroup, which allows /dev/nvidia1 alone. */
    struct env none = {{{NULL, NULL}}};
    CHECK(allocated(root_a, &none, d, n, why, sizeof(why)) == 2 &&
          strstr(why, "/slurm/job_7/step_0") && strstr(why, "/dev/nvidia1"));
    struct env nodev = {{{"CUDA_VISIBLE_DEVICES", "NoDevFiles"}}};
    CHECK(allocated(root_a, &nodev, d, n, why, sizeof(why)) == 2);
    /* A cgroup that allows every device names none. */
    put(root_a, "sys/fs/cgroup/devices/slurm/job_7/step_0/devices.list", "a *:* rwm\n");
    CHECK(allocated(root_a, &none, d, n, why, sizeof(why)) == -1 &&
          strstr(why, "allows every device") && strstr(why, "unset"));
    /* A UUID no device has: the match fails, naming it. */
    struct env e11 = {{{"CUDA_VISIBLE_DEVICES", "GPU-" UUID0}}};
    CHECK(allocated(root_a, &e11, d, 1, why, sizeof(why)) == -1 &&
          strstr(why, "no EGL device has the UUID " UUID0));
}

static void test_allocated_amd(void)
{
    struct gpu_device_names d[2];
    for (int i = 0; i < 2; i++) {
        device_names_init(&d[i], i);
        snprintf(d[i].render_node, sizeof(d[i].render_node), "/dev/dri/renderD%d", 128 + i);
        device_names_from_sysfs(&d[i], root_b);
    }
    CHECK(!strcmp(d[1].bus_id, "0000:c1:00.0") && d[1].nvidia_minor == -1);
    struct sysfs_kfd_gpu kfd[4];
    CHECK(sysfs_kfd_gpus(root_b, kfd, 4) == 2 && kfd[0].node == 1 && kfd[0].render_minor == 129 &&
          !strcmp(kfd[0].bus_id, "0000:c1:00.0") && kfd[1].unique_id == 42);
    char why[2048];
    /* ROCm's GPU 0 is KFD node 1, renderD129: EGL's device 1. */
    struct env e1 = {{{"ROCR_VISIBLE_DEVICES", "0"}}};
    CHECK(allocated(root_b, &e1, d, 2, why, sizeof(why)) == 1 && strstr(why, "KFD node 1"));
    struct env e2 = {{{"GPU_DEVICE_ORDINAL", "1"}}};
    CHECK(allocated(root_b, &e2, d, 2, why, sizeof(why)) == 0);
    /* ROCm's UUID: GPU- and the unique id in hex (1311768467463790320 = 0x123456789abcdef0). */
    struct env e3 = {{{"ROCR_VISIBLE_DEVICES", "GPU-123456789abcdef0"}}};
    CHECK(allocated(root_b, &e3, d, 2, why, sizeof(why)) == 1);
    struct env e4 = {{{"ROCR_VISIBLE_DEVICES", "3"}}};
    CHECK(allocated(root_b, &e4, d, 2, why, sizeof(why)) == -2 && strstr(why, "has 2 GPU node"));
    /* Slurm's index on a box without NVIDIA's driver: the render nodes in order. */
    struct env e5 = {{{"SLURM_JOB_GPUS", "1"}, {"CUDA_VISIBLE_DEVICES", "0"}}};
    CHECK(allocated(root_b, &e5, d, 2, why, sizeof(why)) == 1 && strstr(why, "renderD129"));
    /* CUDA's index on an AMD box counts nothing here: ROCm's is read next. */
    struct env e6 = {{{"CUDA_VISIBLE_DEVICES", "0"}, {"ROCR_VISIBLE_DEVICES", "1"}}};
    CHECK(allocated(root_b, &e6, d, 2, why, sizeof(why)) == 0);
    /* cgroup v2: nothing to read. */
    struct env none = {{{NULL, NULL}}};
    CHECK(allocated(root_b, &none, d, 2, why, sizeof(why)) == -1 && strstr(why, "cgroup v2"));
}

static void test_allocated_no_gpu(void)
{
    /* The test cluster's gres (File=/dev/null) on a box without GPUs. */
    struct gpu_device_names d;
    device_names_init(&d, 0);
    d.software = true;
    device_names_from_sysfs(&d, root_c);
    char why[2048];
    struct env e = {{{"SLURM_JOB_GPUS", "0"}, {"CUDA_VISIBLE_DEVICES", "0"}}};
    CHECK(allocated(root_c, &e, &d, 1, why, sizeof(why)) == -1);
    CHECK(strstr(why, "SLURM_JOB_GPUS=0 names GPU 0, but the node has no GPU device") &&
          strstr(why, "CUDA_VISIBLE_DEVICES=0 names NVIDIA GPU 0") && strstr(why, "default choice"));
    struct env none = {{{NULL, NULL}}};
    CHECK(allocated(root_c, &none, &d, 1, why, sizeof(why)) == -1 && strstr(why, "unset") &&
          strstr(why, "no /proc/self/cgroup"));
}

int main(void)
{
    char tmpl[] = "/tmp/test_devices.XXXXXX";
    const char *base = mkdtemp(tmpl);
    if (!base)
        return 1;
    snprintf(root_a, sizeof(root_a), "%s/a", base);
    snprintf(root_b, sizeof(root_b), "%s/b", base);
    snprintf(root_c, sizeof(root_c), "%s/c", base);
    mkdir(root_a, 0755);
    mkdir(root_b, 0755);
    mkdir(root_c, 0755);
    make_nvidia_box(root_a);
    make_amd_box(root_b);
    test_normalize();
    test_parse();
    test_names_and_match();
    test_allocated_nvidia();
    test_allocated_amd();
    test_allocated_no_gpu();
    char cmd[128];
    snprintf(cmd, sizeof(cmd), "rm -rf '%s'", base);
    if (system(cmd) != 0)
        fprintf(stderr, "could not remove %s\n", base);
    return check_finish("test_devices");
}
