#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <errno.h>
#include <sys/stat.h>
#include <getopt.h>
#include <limits.h>
#include <malloc.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "config.h"
#include "daemon/gpu/egl.h"
#include "common/fsutil.h"
#include "common/clock.h"
#include "daemon/store/records.h"
#include "daemon/api/http.h"
#include "daemon/status/telemetry.h"
#include "daemon/spec/job_cost.h"
#include "daemon/spec/job_spec.h"
#include "common/crash_report.h"
#include "common/log.h"
#include "daemon/jobs/queue.h"
#include "daemon/harness/runner.h"
#include "daemon/jobs/fidelity.h"
#include "daemon/service.h"
#include "daemon/jobs/sweeps.h"
#include "daemon/jobs/assets.h"
#include "daemon/techniques/catalog.h"
#include "daemon/techniques/technique.h"
#include "daemon/effects/effect_info.h"

struct options {
    char listen[256];
    char state_dir[1024];
    char token_file[1024];
    const char *once;
    const char *out;
    const char *port_file;
    struct device_spec device;
    int queue_size;
    int keep_jobs;
    double keep_days;
    int max_connections;
    int max_connections_per_ip;
    double job_timeout;
    double max_job_s;
    double max_frame_s;
    double stall_s;
    double memory_budget_mib; /* 0: the driver, the connections, and half the RAM for a job */
    char asset_dir[1024];      /* --asset-dir: read-only assets; "": none */
    char asset_converter[1024]; /* --asset-converter; "": shadebench-asset beside the daemon */
    double max_asset_bytes;     /* --max-asset-bytes; 0: ASSETS_MAX_BYTES_DEFAULT */
    /* The Khronos reference (fidelity jobs; daemon/jobs/fidelity.h):
     * "": the usual places. */
    char chromium[1024], reference_viewer[1024];
    double reference_timeout, reference_memory_mib; /* 0: the defaults */
    bool list_devices;
    bool json; /* --list-devices --json */
    bool gl_debug;
};

#define DEFAULT_CONFIG "/etc/shadebench/shadebenchd.conf"
/* Retention by default, so that a box left alone keeps its disk and memory
 * bounded: at about 2 MB of files a small job, 10,000 jobs are a few GB
 * (docs/store.md). */
#define KEEP_JOBS_DEFAULT 10000
#define KEEP_JOBS_TEXT "10000"
#define KEEP_DAYS_DEFAULT 90
#define KEEP_DAYS_TEXT "90"
/* /healthz's bound on a busy render thread without progress: far above any
 * step the harness takes between two progress marks (a frame, a slice of
 * GPU work, a metric tile), far below what an operator would wait. */
#define STALL_SECONDS_DEFAULT 60
/* The running time a job gets when it names none: half an hour, far above
 * what the default job takes on a 2-core CPU renderer (docs/api.md) and
 * what every bench script's jobs take, far below the day it was, which let
 * one mistaken job hold the render thread, and every job queued behind it,
 * for a day. */
#define JOB_TIMEOUT_DEFAULT 1800
#define JOB_TIMEOUT_TEXT "1800"
#define STALL_SECONDS_TEXT "60"

static void usage(FILE *f)
{
    fprintf(f,
            "Usage: shadebenchd [OPTION]...\n"
            "Headless OpenGL benchmark daemon: takes shading jobs over HTTP.\n\n"
            "  --listen HOST:PORT   address to serve (default 127.0.0.1:8460; port 0 = any free)\n"
            "  --state-dir DIR      where job results and frames are kept\n"
            "                       (default $STATE_DIRECTORY, else /var/lib/shadebench)\n"
            "  --device DEVICE      the GPU to render on (see --list-devices): an EGL index\n"
            "                       (0), a DRM node (/dev/dri/renderD128) or /dev/nvidiaN, a\n"
            "                       PCI bus id (0000:41:00.0), a UUID (GPU-...), allocated\n"
            "                       (the one the batch scheduler gave: SLURM_STEP_GPUS,\n"
            "                       SLURM_JOB_GPUS, CUDA_VISIBLE_DEVICES, ROCR_VISIBLE_DEVICES,\n"
            "                       GPU_DEVICE_ORDINAL, the device cgroup), or auto (default:\n"
            "                       first hardware device, then software, then surfaceless)\n"
            "  --queue-size N       jobs that may wait at once (default 64)\n"
            "  --token FILE         require \"Authorization: Bearer <token>\" with the token in\n"
            "                       FILE on every endpoint but /healthz (SIGHUP rereads it)\n"
            "  --keep-jobs N        keep the newest N finished jobs (and sweeps), remove older\n"
            "                       ones and their files (default " KEEP_JOBS_TEXT "; 0: keep all)\n"
            "  --keep-days D        remove finished jobs (and sweeps) older than D days\n"
            "                       (default " KEEP_DAYS_TEXT "; 0: keep all)\n"
            "  --job-timeout S      running time a job may take when it gives no timeout_s\n"
            "                       (default " JOB_TIMEOUT_TEXT "; 0: no limit)\n"
            "  --max-job-seconds S  running time any job may take: a larger timeout_s is\n"
            "                       refused, and the default is capped to it (default 0: no\n"
            "                       limit but each job's timeout_s)\n"
            "  --max-frame-seconds S\n"
            "                       the longest one whole frame may hold the render thread:\n"
            "                       a job whose frame measures more fails before timing\n"
            "                       unless it sets accept_sliced_timing (default 2; 0: no\n"
            "                       bound)\n"
            "  --stall-seconds S    /healthz answers 503 when the render thread, busy with a\n"
            "                       job, has made no progress for S seconds (default "
            STALL_SECONDS_TEXT "; 0: never)\n"
            "  --memory-budget MIB  the daemon's memory budget: a job whose estimate does not fit\n"
            "                       what the driver (measured at start) and the connections\n"
            "                       leave of it is refused (default: those two and half the\n"
            "                       machine's memory for a job)\n"
            "  --max-connections N  HTTP connections open at once, in total (default 4096)\n"
            "  --max-connections-per-ip N\n"
            "                       HTTP connections open at once from one address (default 64)\n"
            "  --max-asset-bytes N  the largest asset file PUT /v1/assets/NAME takes (default\n"
            "                       268435456, 256 MiB)\n"
            "  --asset-dir DIR      a read-only folder of .glb and .gltf files, each an asset\n"
            "                       named by its file name (converted in the background at start)\n"
            "  --asset-converter PATH\n"
            "                       the glTF converter (default: shadebench-asset beside this\n"
            "                       executable)\n"
            "  --chromium PATH      Chromium for the Khronos reference (default: chromium or\n"
            "                       chromium-browser on PATH)\n"
            "  --reference-viewer DIR\n"
            "                       the vendored Khronos glTF Sample Viewer (default:\n"
            "                       reference-viewer beside this executable, else\n"
            "                       ../share/shadebench/reference-viewer)\n"
            "  --reference-timeout S  wall clock the reference may take (default 300)\n"
            "  --reference-memory MIB resident memory of Chromium and its helpers\n"
            "                       (default 4096)\n"
            "  --config FILE        settings file (default " DEFAULT_CONFIG " if present)\n"
            "  --port-file FILE     write the bound port to FILE once listening\n"
            "  --list-devices       print the EGL devices with their names and exit (--json:\n"
            "                       as JSON)\n"
            "  --once JOB.json      run one job without HTTP, then exit\n"
            "  --out DIR            with --once: where result.json, job.json, task.json and\n"
            "                       frames go (written whole: renamed into place at the end)\n"
            "  --gl-debug           request a debug GL context\n"
            "  --log-level LEVEL    debug, info, warn or error (default info)\n"
            "  --version, --help\n\n"
            "Settings come from, in rising order: defaults, the config file (lines of\n"
            "\"key = value\": listen, state-dir, device, queue-size, token, keep-jobs,\n"
            "keep-days, job-timeout, max-job-seconds, max-frame-seconds, stall-seconds,\n"
            "memory-budget, max-connections, max-connections-per-ip, max-asset-bytes,\n"
            "asset-dir, asset-converter, chromium, reference-viewer, reference-timeout,\n"
            "reference-memory, log-level), the environment\n"
            "(SHADEBENCH_LISTEN, SHADEBENCH_STATE_DIR, SHADEBENCH_DEVICE,\n"
            "SHADEBENCH_QUEUE_SIZE, SHADEBENCH_TOKEN_FILE, SHADEBENCH_KEEP_JOBS,\n"
            "SHADEBENCH_KEEP_DAYS, SHADEBENCH_JOB_TIMEOUT, SHADEBENCH_MAX_JOB_SECONDS,\n"
            "SHADEBENCH_MAX_FRAME_SECONDS, "
            "SHADEBENCH_STALL_SECONDS, SHADEBENCH_MEMORY_BUDGET,\n"
            "SHADEBENCH_MAX_CONNECTIONS, SHADEBENCH_MAX_CONNECTIONS_PER_IP,\n"
            "SHADEBENCH_MAX_ASSET_BYTES, SHADEBENCH_ASSET_DIR, SHADEBENCH_ASSET_CONVERTER,\n"
            "SHADEBENCH_CHROMIUM, SHADEBENCH_REFERENCE_VIEWER, SHADEBENCH_REFERENCE_TIMEOUT,\n"
            "SHADEBENCH_REFERENCE_MEMORY, SHADEBENCH_LOG_LEVEL), the flags.\n");
}

static bool parse_int(const char *s, int min, int max, int *out)
{
    char *end;
    long v = strtol(s, &end, 10);
    if (!*s || *end || v < min || v > max)
        return false;
    *out = (int)v;
    return true;
}

static bool parse_number(const char *s, double min, double max, double *out)
{
    char *end;
    double v = strtod(s, &end);
    if (!*s || *end || !(v >= min && v <= max))
        return false;
    *out = v;
    return true;
}

/* One setting by name, from any source; origin names it in errors. */
static bool apply_setting(struct options *o, const char *key, const char *value,
                          const char *origin)
{
    const char *rule = NULL;
    if (strcmp(key, "listen") == 0)
        snprintf(o->listen, sizeof(o->listen), "%s", value);
    else if (strcmp(key, "state-dir") == 0)
        snprintf(o->state_dir, sizeof(o->state_dir), "%s", value);
    else if (strcmp(key, "token") == 0 || strcmp(key, "token-file") == 0)
        snprintf(o->token_file, sizeof(o->token_file), "%s", value);
    else if (strcmp(key, "device") == 0) {
        static char why[600];
        if (!device_spec_parse(value, &o->device, why, sizeof(why)))
            rule = why;
    } else if (strcmp(key, "queue-size") == 0) {
        if (!parse_int(value, 1, 100000, &o->queue_size))
            rule = "must be an integer from 1 to 100000";
    } else if (strcmp(key, "keep-jobs") == 0) {
        if (!parse_int(value, 0, 100000000, &o->keep_jobs))
            rule = "must be an integer from 0 (keep all)";
    } else if (strcmp(key, "keep-days") == 0) {
        if (!parse_number(value, 0, 1e6, &o->keep_days))
            rule = "must be a number of days from 0 (keep all)";
    } else if (strcmp(key, "job-timeout") == 0) {
        if (!parse_number(value, 0, 1e7, &o->job_timeout))
            rule = "must be a number of seconds from 0 (no limit) to 10000000";
    } else if (strcmp(key, "max-frame-seconds") == 0) {
        if (!parse_number(value, 0, 1e6, &o->max_frame_s))
            rule = "must be a number of seconds from 0 (no bound) to 1000000";
    } else if (strcmp(key, "max-job-seconds") == 0) {
        if (!parse_number(value, 0, 1e7, &o->max_job_s))
            rule = "must be a number of seconds from 0 (no limit) to 10000000";
    } else if (strcmp(key, "stall-seconds") == 0) {
        if (!parse_number(value, 0, 1e6, &o->stall_s))
            rule = "must be a number of seconds from 0 (never stalled) to 1000000";
    } else if (strcmp(key, "memory-budget") == 0) {
        if (!parse_number(value, 0, 1e9, &o->memory_budget_mib))
            rule = "must be a number of MiB from 0 (the default) to 1000000000";
    } else if (strcmp(key, "max-connections") == 0) {
        if (!parse_int(value, 16, 1000000, &o->max_connections))
            rule = "must be an integer from 16 to 1000000";
    } else if (strcmp(key, "max-connections-per-ip") == 0) {
        if (!parse_int(value, 1, 1000000, &o->max_connections_per_ip))
            rule = "must be an integer from 1 to 1000000";
    } else if (strcmp(key, "max-asset-bytes") == 0) {
        if (!parse_number(value, 1, 1099511627776.0, &o->max_asset_bytes) ||
            o->max_asset_bytes != (double)(uint64_t)o->max_asset_bytes)
            rule = "must be a whole number of bytes from 1 to 1099511627776 (1 TiB)";
    } else if (strcmp(key, "asset-dir") == 0) {
        snprintf(o->asset_dir, sizeof(o->asset_dir), "%s", value);
    } else if (strcmp(key, "asset-converter") == 0) {
        snprintf(o->asset_converter, sizeof(o->asset_converter), "%s", value);
    } else if (strcmp(key, "chromium") == 0) {
        snprintf(o->chromium, sizeof(o->chromium), "%s", value);
    } else if (strcmp(key, "reference-viewer") == 0) {
        snprintf(o->reference_viewer, sizeof(o->reference_viewer), "%s", value);
    } else if (strcmp(key, "reference-timeout") == 0) {
        if (!parse_number(value, 1, 86400, &o->reference_timeout))
            rule = "must be a number of seconds from 1 to 86400";
    } else if (strcmp(key, "reference-memory") == 0) {
        if (!parse_number(value, 64, 1e7, &o->reference_memory_mib))
            rule = "must be a number of MiB from 64 to 10000000";
    } else if (strcmp(key, "log-level") == 0) {
        static const char *const levels[] = {"debug", "info", "warn", "error"};
        rule = "must be debug, info, warn or error";
        for (int i = 0; i < 4; i++)
            if (strcmp(value, levels[i]) == 0) {
                log_set_level((enum log_level)i);
                rule = NULL;
            }
    } else {
        fprintf(stderr, "shadebenchd: %s: unknown setting %s\n", origin, key);
        return false;
    }
    if (rule)
        fprintf(stderr, "shadebenchd: %s: %s %s\n", origin, key, rule);
    return rule == NULL;
}

static char *trim(char *s)
{
    while (*s == ' ' || *s == '\t')
        s++;
    char *end = s + strlen(s);
    while (end > s && (end[-1] == ' ' || end[-1] == '\t' || end[-1] == '\n' || end[-1] == '\r'))
        *--end = '\0';
    return s;
}

static bool load_config(struct options *o, const char *path, bool required)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        if (required)
            fprintf(stderr, "shadebenchd: cannot read the config file %s\n", path);
        return !required;
    }
    char line[2048], origin[1100];
    bool ok = true;
    for (int n = 1; ok && fgets(line, sizeof(line), f); n++) {
        char *l = trim(line);
        if (!*l || *l == '#')
            continue;
        char *eq = strchr(l, '=');
        snprintf(origin, sizeof(origin), "%s:%d", path, n);
        if (!eq) {
            fprintf(stderr, "shadebenchd: %s: expected \"key = value\"\n", origin);
            ok = false;
            break;
        }
        *eq = '\0';
        ok = apply_setting(o, trim(l), trim(eq + 1), origin);
    }
    fclose(f);
    return ok;
}

static bool load_environment(struct options *o)
{
    static const char *const keys[] = {"listen", "state-dir", "device", "queue-size",
                                       "token-file", "keep-jobs", "keep-days", "job-timeout",
                                       "max-job-seconds", "max-frame-seconds", "stall-seconds", "memory-budget", "max-connections",
                                       "max-connections-per-ip", "max-asset-bytes", "asset-dir",
                                       "asset-converter", "chromium", "reference-viewer",
                                       "reference-timeout", "reference-memory", "log-level",
                                       NULL};
    for (const char *const *k = keys; *k; k++) {
        char name[64] = "SHADEBENCH_";
        size_t n = strlen(name);
        for (const char *c = *k; *c && n < sizeof(name) - 1; c++)
            name[n++] = *c == '-' ? '_' : (char)(*c - 'a' + 'A');
        name[n] = '\0';
        const char *v = getenv(name);
        if (v && *v && !apply_setting(o, *k, v, name))
            return false;
    }
    return true;
}

/* Reads the bearer token (surrounding whitespace dropped). A token that
 * would not survive an HTTP header intact, or is longer than the server
 * compares, is refused here with the reason rather than cut. */
static bool read_token(const char *path, char *token, size_t cap)
{
    size_t len = 0;
    char *text = fs_read_file(path, 65536, &len);
    if (!text) {
        LOG(LOG_ERROR, "cannot read the token file %s", path);
        return false;
    }
    const char *t = trim(text);
    size_t n = strlen(t);
    const char *why = NULL;
    if (n == 0)
        why = "it is empty";
    else if (n >= cap)
        why = "it is longer than the 4096 bytes a token may have";
    for (size_t i = 0; !why && i < n; i++)
        if ((unsigned char)t[i] <= 0x20 || (unsigned char)t[i] >= 0x7f)
            why = "it must be printable ASCII without spaces";
    if (why)
        LOG(LOG_ERROR, "the token in %s (%zu bytes) is refused: %s", path, n, why);
    else
        memcpy(token, t, n + 1);
    free(text);
    return why == NULL;
}

/* Every HTTP connection is a descriptor: let the daemon open as many as its
 * hard limit allows (systemd's default soft limit is 1024). */
static rlim_t raise_fd_limit(void)
{
    struct rlimit rl;
    if (getrlimit(RLIMIT_NOFILE, &rl) != 0)
        return 1024;
    if (rl.rlim_cur < rl.rlim_max) {
        rl.rlim_cur = rl.rlim_max;
        if (setrlimit(RLIMIT_NOFILE, &rl) != 0)
            getrlimit(RLIMIT_NOFILE, &rl);
    }
    return rl.rlim_cur;
}

/* --list-devices: each EGL device with the names --device takes, opened
 * briefly for its GL renderer and version; as text or JSON. */
static int list_devices(bool as_json)
{
    struct gpu_device_names devs[16];
    char err[256] = "";
    int n = egl_list_devices(devs, 16, err, sizeof(err));
    json_t *list = json_array();
    if (n < 0) {
        if (!as_json)
            printf("no EGL device enumeration: %s\n", err);
        n = 0;
    }
    for (int i = 0; i < n; i++) {
        char why[512] = "", version[128] = "";
        bool opened = egl_probe_device(i, &devs[i], version, sizeof(version), why, sizeof(why));
        json_t *j = device_names_json(&devs[i]);
        json_object_set_new(j, "gl_version", opened ? json_string(version) : json_null());
        json_object_set_new(j, "opens", json_boolean(opened));
        if (!opened)
            json_object_set_new(j, "error", json_string(why));
        json_array_append_new(list, j);
        if (as_json)
            continue;
        const struct gpu_device_names *d = &devs[i];
        printf("%d: %s%s%s\n", i, d->renderer[0] ? d->renderer : "?",
               d->software ? " (software)" : "", opened ? "" : " (no GL 4.3 context)");
        printf("    vendor       %s\n", d->vendor[0] ? d->vendor : "-");
        printf("    GL version   %s\n", opened ? version : why);
        printf("    DRM node     %s%s%s\n", d->render_node[0] ? d->render_node : "-",
               d->drm_node[0] ? "  " : "", d->drm_node);
        printf("    PCI bus id   %s%s%s%s\n", d->bus_id[0] ? d->bus_id : "-",
               d->bus_id[0] ? "  (from " : "", d->bus_id_from, d->bus_id[0] ? ")" : "");
        printf("    UUID         %s%s%s%s\n", d->uuid[0] ? d->uuid : "-",
               d->uuid[0] ? "  (from " : "", d->uuid_from, d->uuid[0] ? ")" : "");
        if (d->cuda_device >= 0 || d->nvidia_minor >= 0)
            printf("    NVIDIA       CUDA device %d, /dev/nvidia%d\n", d->cuda_device,
                   d->nvidia_minor);
        printf("    --device     %d", i);
        if (d->render_node[0])
            printf(", %s", d->render_node);
        if (d->nvidia_minor >= 0)
            printf(", /dev/nvidia%d", d->nvidia_minor);
        if (d->bus_id[0])
            printf(", %s", d->bus_id);
        if (d->uuid[0])
            printf(", GPU-%s", d->uuid);
        printf("\n");
    }
    if (as_json) {
        json_t *doc = json_pack("{s:o}", "devices", list);
        if (!json_array_size(list))
            json_object_set_new(doc, "error", json_string(err));
        json_dumpf(doc, stdout, JSON_INDENT(2));
        putchar('\n');
        json_decref(doc);
    } else {
        json_decref(list);
    }
    return 0;
}

/* What ran where, for a fleet's gathering: the node, the exit status and,
 * under Slurm, the job and array task ids from its environment. */
static json_t *once_task_json(const char *status, int rc, double started, double finished)
{
    char host[256] = "";
    if (gethostname(host, sizeof(host) - 1) != 0)
        host[0] = '\0';
    json_t *t = json_pack("{s:s, s:s, s:i, s:f, s:f}", "node", host, "status", status, "exit_status",
                          rc, "started_unix", started, "finished_unix", finished);
    static const char *const slurm[][2] = {
        {"job_id", "SLURM_JOB_ID"},           {"array_job_id", "SLURM_ARRAY_JOB_ID"},
        {"array_task_id", "SLURM_ARRAY_TASK_ID"}, {"restart_count", "SLURM_RESTART_COUNT"},
        {"partition", "SLURM_JOB_PARTITION"}, {"node", "SLURMD_NODENAME"},
        {"gpus", "SLURM_JOB_GPUS"},           {"step_gpus", "SLURM_STEP_GPUS"},
        {"cuda_visible_devices", "CUDA_VISIBLE_DEVICES"},
        {"rocr_visible_devices", "ROCR_VISIBLE_DEVICES"},
        {"gpu_device_ordinal", "GPU_DEVICE_ORDINAL"},
    };
    json_t *sl = json_object();
    for (size_t i = 0; i < sizeof(slurm) / sizeof(slurm[0]); i++) {
        const char *v = getenv(slurm[i][1]);
        if (v && v[0])
            json_object_set_new(sl, slurm[i][0], json_string(v));
    }
    if (json_object_size(sl))
        json_object_set_new(t, "slurm", sl);
    else
        json_decref(sl);
    return t;
}

/* --out DIR appears whole or not at all: the job renders into a sibling
 * DIR.partial-HOST-PID, which is renamed to DIR once job.json and task.json
 * are in it, so that a fleet's gathering never reads a half-written folder
 * whatever kills the task (a partial folder is what a killed one leaves). */
static bool once_publish(const char *partial, const char *out)
{
    if (rename(partial, out) == 0)
        return true;
    if (errno != EEXIST && errno != ENOTEMPTY)
        return false;
    char old[PATH_MAX + 64];
    snprintf(old, sizeof(old), "%s.old-%ld", out, (long)getpid());
    if (rename(out, old) != 0 || rename(partial, out) != 0)
        return false;
    record_remove_dir(old);
    return true;
}

/* An --out folder that may be replaced: absent, empty, or a result folder
 * (a job's files only: no subfolder, and its result.json or job.json). */
static bool once_replaceable(const char *out)
{
    DIR *d = opendir(out);
    if (!d)
        return errno == ENOENT;
    bool any = false, result = false, foreign = false;
    struct dirent *e;
    char path[PATH_MAX + 300];
    while ((e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
            continue;
        any = true;
        result = result || !strcmp(e->d_name, "result.json") || !strcmp(e->d_name, "job.json");
        snprintf(path, sizeof(path), "%s/%s", out, e->d_name);
        struct stat st;
        foreign = foreign || lstat(path, &st) != 0 || !S_ISREG(st.st_mode);
    }
    closedir(d);
    return !any || (result && !foreign);
}

static int run_once(const struct options *o, const struct technique_catalog *catalog)
{
    size_t len = 0;
    double started = clock_unix_s();
    char *text = fs_read_file(o->once, JOB_MAX_BODY_BYTES + 1, &len);
    if (!text) {
        fprintf(stderr, "shadebenchd: cannot read %s\n", o->once);
        return 2;
    }
    struct job_spec spec;
    struct job_error jerr;
    bool ok = len <= JOB_MAX_BODY_BYTES &&
              job_spec_parse_text(text, len, catalog, &spec, &jerr);
    free(text);
    if (!ok) {
        if (len > JOB_MAX_BODY_BYTES)
            fprintf(stderr, "shadebenchd: %s: the job must be at most 65536 bytes\n", o->once);
        else
            fprintf(stderr, "shadebenchd: %s: %s: %s\n", o->once, jerr.field, jerr.message);
        return 2;
    }
    char host[64] = "";
    if (gethostname(host, sizeof(host) - 1) != 0)
        snprintf(host, sizeof(host), "host");
    /* The folder is replaced whole, so it must be one: not "/" or ".", and
     * not a folder of other files. */
    char out[PATH_MAX];
    snprintf(out, sizeof(out), "%s", o->out);
    size_t out_len = strlen(out);
    while (out_len > 1 && out[out_len - 1] == '/')
        out[--out_len] = '\0';
    const char *base = strrchr(out, '/') ? strrchr(out, '/') + 1 : out;
    if (!strcmp(base, "") || !strcmp(base, ".") || !strcmp(base, "..")) {
        fprintf(stderr, "shadebenchd: --out %s: name a folder of its own for the result\n", o->out);
        return 2;
    }
    if (!once_replaceable(out)) {
        fprintf(stderr, "shadebenchd: --out %s holds other files than a result: choose a new or "
                        "empty folder, or one --once wrote\n", o->out);
        return 2;
    }
    char partial[PATH_MAX];
    if ((size_t)snprintf(partial, sizeof(partial), "%s.partial-%s-%ld", out, host,
                         (long)getpid()) >= sizeof(partial)) {
        fprintf(stderr, "shadebenchd: --out %s: the path is too long\n", o->out);
        return 2;
    }
    if (!fs_mkdir_p(partial)) {
        fprintf(stderr, "shadebenchd: cannot create %s: %s\n", partial, strerror(errno));
        return 2;
    }
    char err[PATH_MAX + 300];
    /* One job, no state directory: its record lives in memory. */
    struct store *store = store_open(NULL, err, sizeof(err));
    struct queue *q = store ? queue_create(store, 1) : NULL;
    struct runner *r = q ? runner_create(q, &o->device, o->gl_debug, err, sizeof(err)) : NULL;
    if (!r) {
        fprintf(stderr, "shadebenchd: %s\n", q || !store ? err : "out of memory");
        queue_destroy(q);
        store_close(store);
        record_remove_dir(partial);
        return 1;
    }
    char id[24];
    int rc = 1;
    if (queue_submit(q, &spec, partial, id) == QUEUE_OK) {
        json_t *job;
        const char *status = "running";
        for (;;) {
            job = queue_job_json(q, id, 3600);
            status = json_string_value(json_object_get(job, "status"));
            if (strcmp(status, "queued") != 0 && strcmp(status, "running") != 0)
                break;
            json_decref(job);
        }
        json_dumpf(job, stdout, JSON_INDENT(2));
        putchar('\n');
        rc = strcmp(status, "done") == 0 ? 0 : 1;
        char path[PATH_MAX + 32];
        snprintf(path, sizeof(path), "%s/job.json", partial);
        json_t *task = once_task_json(status, rc, started, clock_unix_s());
        bool written = fs_write_json_atomic(path, job);
        snprintf(path, sizeof(path), "%s/task.json", partial);
        written = written && fs_write_json_atomic(path, task);
        json_decref(task);
        if (!written || !once_publish(partial, out)) {
            fprintf(stderr, "shadebenchd: cannot write %s: %s\n", written ? o->out : path,
                    strerror(errno));
            rc = 2;
        }
        json_decref(job);
    } else {
        fprintf(stderr, "shadebenchd: cannot create the job in %s\n", partial);
        record_remove_dir(partial);
    }
    runner_destroy(r);
    queue_destroy(q);
    store_close(store);
    return rc;
}

/* SIGTERM waits this long for the render thread, then exits without it. */
#define STOP_RENDER_WAIT_S 2

/* The memory budget (/v1/info): the driver's part is the resident set now,
 * with the GL context up; what the driver and the connections leave is
 * what one job may take (job_cost.h), and job_spec_parse refuses a job
 * whose estimate is over it. false with err when --memory-budget leaves a
 * job less than 64 MiB. */
static bool set_memory_budget(const struct options *o, const struct http_limits *limits,
                              double *budget, double *driver, char *err, size_t errlen)
{
    *driver = telemetry_rss_bytes();
    double http = http_memory_bytes(limits), job;
    if (o->memory_budget_mib > 0) {
        *budget = o->memory_budget_mib * 1048576.0;
        job = *budget - *driver - http;
        if (job < 64.0 * 1048576.0) {
            snprintf(err, errlen, "--memory-budget %.0f MiB leaves %.0f MiB for a job once the "
                     "driver (%.0f MiB measured) and %u connections (%.0f MiB) have theirs; a "
                     "job needs at least 64", o->memory_budget_mib, job / 1048576.0,
                     *driver / 1048576.0, limits->max_connections, http / 1048576.0);
            return false;
        }
    } else {
        job = (double)sysconf(_SC_PHYS_PAGES) * (double)sysconf(_SC_PAGESIZE) / 2;
        *budget = *driver + http + job;
    }
    job_cost_set_memory_limit(job);
    LOG(LOG_INFO, "memory budget %.0f MiB: the driver %.0f (measured), connections %.0f, a job "
        "up to %.0f", *budget / 1048576.0, *driver / 1048576.0, http / 1048576.0,
        job / 1048576.0);
    return true;
}

/* The device's MSAA limit for job_spec_parse, so that a job over it is
 * refused naming msaa when it is submitted rather than failing when it
 * runs (jobs queued before a restart are checked by the harness). */
static void set_max_msaa(struct runner *r)
{
    json_t *device = runner_device_json(r);
    json_t *m = json_object_get(json_object_get(device, "caps"), "max_msaa");
    if (json_is_integer(m))
        job_spec_set_max_msaa((int)json_integer_value(m));
    json_decref(device);
}

/* The render thread as the HTTP layer sees it (http.h). */
static void render_state(void *r, struct render_state *out) { runner_state(r, out); }
static json_t *render_device_json(void *r) { return runner_device_json(r); }

static int serve(const struct options *o, const struct technique_catalog *catalog)
{
    char state_dir[PATH_MAX], token[HTTP_MAX_TOKEN_BYTES + 1] = "";
    const char *env = getenv("STATE_DIRECTORY");
    snprintf(state_dir, sizeof(state_dir), "%s",
             o->state_dir[0] ? o->state_dir : (env && *env ? env : "/var/lib/shadebench"));
    if (o->token_file[0] && !read_token(o->token_file, token, sizeof(token)))
        return 1;
    struct http_limits limits;
    http_limits_defaults(&limits);
    if (o->max_connections)
        limits.max_connections = (unsigned)o->max_connections;
    if (o->max_connections_per_ip)
        limits.max_connections_per_ip = (unsigned)o->max_connections_per_ip;
    /* Tests only: a shorter window over which an upload must keep up the
     * minimum rate, so that e2e_upload_slots sees a slow one cut sooner. */
    const char *window = getenv("SHADEBENCH_DEBUG_UPLOAD_WINDOW_S");
    if (window && atof(window) > 0)
        limits.upload_window_s = atof(window);
    rlim_t fds = raise_fd_limit();
    if (fds != RLIM_INFINITY && limits.max_connections + 64 > fds) {
        LOG(LOG_WARN, "--max-connections %u lowered to %u: only %llu file descriptors allowed",
            limits.max_connections, (unsigned)(fds > 128 ? fds - 64 : 64),
            (unsigned long long)fds);
        limits.max_connections = (unsigned)(fds > 128 ? fds - 64 : 64);
    }
    if (!fs_mkdir_p(state_dir)) {
        LOG(LOG_ERROR, "cannot create the state directory %s", state_dir);
        return 1;
    }
    /* Signals are taken by sigwait below, never by the render or HTTP threads. */
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGHUP);
    pthread_sigmask(SIG_BLOCK, &set, NULL);
    signal(SIGPIPE, SIG_IGN);

    char err[PATH_MAX + 300];
    int rc = 1;
    struct queue *q = NULL;
    struct runner *r = NULL;
    struct fidelity *fidelity = NULL;
    struct assets *assets = NULL;
    struct sweeps *sweeps = NULL;
    struct http_server *http = NULL;
    struct store *store = store_open(state_dir, err, sizeof(err));
    if (!store) {
        LOG(LOG_ERROR, "%s", err);
        return 1;
    }
    q = queue_create(store, o->queue_size);
    if (!q) {
        LOG(LOG_ERROR, "out of memory");
        goto out;
    }
    queue_set_retention(q, o->keep_jobs, o->keep_days);
    /* Earlier jobs first: finished ones are served from the store, queued
     * ones run. */
    int loaded = queue_load(q, catalog, err, sizeof(err));
    if (loaded < 0) {
        LOG(LOG_ERROR, "%s", err);
        goto out;
    }
    if (loaded > 0)
        LOG(LOG_INFO, "%d job(s) in %s/%s", loaded, state_dir, STORE_FILE);
    /* Before the render thread: it hands fidelity jobs to this worker. */
    const struct fidelity_config fcfg = {
        .state_dir = state_dir, .chromium = o->chromium, .viewer_dir = o->reference_viewer,
        .timeout_s = o->reference_timeout,
        .memory_bytes = (uint64_t)(o->reference_memory_mib * 1048576.0)};
    fidelity = fidelity_create(&fcfg, q);
    if (!fidelity) {
        LOG(LOG_ERROR, "cannot start the fidelity worker");
        goto out;
    }
    runner_use_fidelity(fidelity);
    r = runner_create(q, &o->device, o->gl_debug, err, sizeof(err));
    if (!r) {
        LOG(LOG_ERROR, "%s", err);
        goto out;
    }
    set_max_msaa(r);
    double budget, driver;
    if (!set_memory_budget(o, &limits, &budget, &driver, err, sizeof(err))) {
        LOG(LOG_ERROR, "%s", err);
        goto out;
    }
    /* After queue_load: a queued job's pinned asset keeps its files. */
    struct assets_config acfg = {.state_dir = state_dir, .asset_dir = o->asset_dir,
                                 .converter = o->asset_converter,
                                 .max_asset_bytes = o->max_asset_bytes > 0
                                                        ? (uint64_t)o->max_asset_bytes
                                                        : ASSETS_MAX_BYTES_DEFAULT};
    asset_limits_defaults(&acfg.limits);
    acfg.limits.max_file_bytes = acfg.max_asset_bytes;
    asset_run_limits_defaults(&acfg.run);
    assets = assets_create(&acfg, store, q, err, sizeof(err));
    if (!assets) {
        LOG(LOG_ERROR, "%s", err);
        goto out;
    }
    struct queue_asset_hooks hooks;
    assets_queue_hooks(assets, &hooks);
    queue_set_asset_hooks(q, &hooks);
    sweeps = sweeps_create(q, catalog);
    if (!sweeps) {
        LOG(LOG_ERROR, "cannot start the sweep thread");
        goto out;
    }
    /* The resumed sweeps hold their hashes now: what nothing holds goes. */
    assets_release_unused(assets);
    const struct http_context http_ctx = {.catalog = catalog, .queue = q, .sweeps = sweeps,
                                          .assets = assets, .fidelity = fidelity,
                                          .render_state = render_state,
                                          .device_json = render_device_json, .render = r,
                                          .stall_s = o->stall_s, .memory_budget_bytes = budget,
                                          .driver_bytes = driver};
    http = http_server_create(o->listen, &limits, &http_ctx, err, sizeof(err));
    if (!http) {
        LOG(LOG_ERROR, "%s", err);
        goto out;
    }
    LOG(LOG_INFO, "shadebenchd %s listening on %s (port %d), state in %s", PACKAGE_VERSION,
        o->listen, http_server_port(http), state_dir);
    if (o->port_file) {
        char buf[16];
        int n = snprintf(buf, sizeof(buf), "%d\n", http_server_port(http));
        if (!fs_write_atomic(o->port_file, buf, (size_t)n))
            LOG(LOG_WARN, "cannot write %s", o->port_file);
    }
    http_server_set_token(http, token);
    service_ready();
    int sig = 0;
    for (;;) {
        sigwait(&set, &sig);
        if (sig != SIGHUP)
            break;
        /* SIGHUP: reread the token so that it can be rotated without a restart. */
        if (o->token_file[0] && read_token(o->token_file, token, sizeof(token)) &&
            http_server_set_token(http, token)) {
            LOG(LOG_INFO, "SIGHUP: token reread from %s", o->token_file);
        } else {
            LOG(LOG_INFO, "SIGHUP: %s", o->token_file[0] ? "the token is unchanged"
                                                         : "nothing to reload");
        }
    }
    LOG(LOG_INFO, "signal %d: stopping", sig);
    service_stopping();
    rc = 0;
out:
    http_server_destroy(http);
    sweeps_destroy(sweeps);
    if (assets)
        queue_set_asset_hooks(q, NULL); /* the render thread may still end a job */
    assets_destroy(assets);
    /* A stop (not a failed start): within a few seconds whatever runs
     * (systemd's stop timeout is longer): the running job is back in the
     * queue once the render thread stops it, and a frame still draining on
     * the GPU is not waited for. */
    if (rc == 0 && !runner_stop(r, STOP_RENDER_WAIT_S)) {
        queue_store_abandoned(q);
        LOG(LOG_WARN, "the render thread is still draining GPU work after %d s; exiting without "
            "it (every job's state is stored)", STOP_RENDER_WAIT_S);
        _exit(0);
    }
    runner_destroy(r);
    fidelity_destroy(fidelity);
    queue_destroy(q);
    store_close(store);
    return rc;
}

int main(int argc, char **argv)
{
    /* Measurement integrity, set before any thread starts: glibc raises its
     * mmap and trim thresholds as it frees large blocks, and the first job
     * after a larger one then ran its frames up to 3 times slower (the heap
     * top trimmed and faulted back in every frame). Fixed thresholds keep a
     * job's timings independent of the jobs before it, for at most 128 MiB
     * of free heap kept. And one arena, so that those thresholds govern
     * every allocation: the render thread's own arena is a chain of 64 MiB
     * heaps, and glibc unmaps a heap whose memory is all free whatever the
     * trim threshold, so llvmpipe's vertex buffer of a draw (28 MiB for the
     * default scene) now and then landed in a fresh heap, unmapped at its
     * free and faulted back in at the next draw: 7,100 page faults a time,
     * 0 to 85,000 in the 20 timed frames of a 160x120 job, with no larger
     * job before it, as the other threads' allocations happened to lie
     * (e2e_integrity's bound of 20,000 failed on it). With one arena: 9 to
     * 48 in the same jobs. */
    mallopt(M_ARENA_MAX, 1);
    mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024);
    mallopt(M_TRIM_THRESHOLD, 128 * 1024 * 1024);
    crash_report_install("shadebenchd");
    /* Built before any thread starts, then read-only: every registered
     * technique and effect checked once. */
    static struct technique_catalog catalog;
    char catalog_err[256];
    if (!technique_catalog_init(&catalog, catalog_err, sizeof(catalog_err)) ||
        !technique_registry_check(catalog_err, sizeof(catalog_err)) ||
        !effect_registry_check(catalog_err, sizeof(catalog_err))) {
        fprintf(stderr, "shadebenchd: %s\n", catalog_err);
        return 1;
    }
    struct options o = {.device = {.kind = DEVICE_SPEC_AUTO, .text = "auto"}, .queue_size = 64, .job_timeout = JOB_TIMEOUT_DEFAULT,
                        .max_frame_s = JOB_DEFAULT_MAX_FRAME_S,
                        .stall_s = STALL_SECONDS_DEFAULT,
                        .keep_jobs = KEEP_JOBS_DEFAULT, .keep_days = KEEP_DAYS_DEFAULT};
    snprintf(o.listen, sizeof(o.listen), "127.0.0.1:8460");
    enum { OPT_LISTEN = 256, OPT_STATE, OPT_DEVICE, OPT_QUEUE, OPT_TOKEN, OPT_KEEP_JOBS,
           OPT_KEEP_DAYS, OPT_JOB_TIMEOUT, OPT_MAX_JOB, OPT_MAX_FRAME, OPT_STALL, OPT_MEMORY, OPT_MAX_CONN, OPT_MAX_CONN_IP, OPT_MAX_ASSET, OPT_ASSET_DIR, OPT_ASSET_CONV, OPT_CHROMIUM, OPT_REF_VIEWER, OPT_REF_TIMEOUT, OPT_REF_MEMORY, OPT_CONFIG, OPT_PORT_FILE, OPT_LIST, OPT_JSON, OPT_ONCE, OPT_OUT, OPT_DEBUG,
           OPT_LOG, OPT_VERSION, OPT_HELP };
    static const struct option longopts[] = {
        {"listen", required_argument, NULL, OPT_LISTEN},
        {"state-dir", required_argument, NULL, OPT_STATE},
        {"device", required_argument, NULL, OPT_DEVICE},
        {"queue-size", required_argument, NULL, OPT_QUEUE},
        {"token", required_argument, NULL, OPT_TOKEN},
        {"keep-jobs", required_argument, NULL, OPT_KEEP_JOBS},
        {"keep-days", required_argument, NULL, OPT_KEEP_DAYS},
        {"job-timeout", required_argument, NULL, OPT_JOB_TIMEOUT},
        {"max-job-seconds", required_argument, NULL, OPT_MAX_JOB},
        {"max-frame-seconds", required_argument, NULL, OPT_MAX_FRAME},
        {"stall-seconds", required_argument, NULL, OPT_STALL},
        {"memory-budget", required_argument, NULL, OPT_MEMORY},
        {"max-connections", required_argument, NULL, OPT_MAX_CONN},
        {"max-connections-per-ip", required_argument, NULL, OPT_MAX_CONN_IP},
        {"max-asset-bytes", required_argument, NULL, OPT_MAX_ASSET},
        {"asset-dir", required_argument, NULL, OPT_ASSET_DIR},
        {"asset-converter", required_argument, NULL, OPT_ASSET_CONV},
        {"chromium", required_argument, NULL, OPT_CHROMIUM},
        {"reference-viewer", required_argument, NULL, OPT_REF_VIEWER},
        {"reference-timeout", required_argument, NULL, OPT_REF_TIMEOUT},
        {"reference-memory", required_argument, NULL, OPT_REF_MEMORY},
        {"config", required_argument, NULL, OPT_CONFIG},
        {"port-file", required_argument, NULL, OPT_PORT_FILE},
        {"list-devices", no_argument, NULL, OPT_LIST},
        {"json", no_argument, NULL, OPT_JSON},
        {"once", required_argument, NULL, OPT_ONCE},
        {"out", required_argument, NULL, OPT_OUT},
        {"gl-debug", no_argument, NULL, OPT_DEBUG},
        {"log-level", required_argument, NULL, OPT_LOG},
        {"version", no_argument, NULL, OPT_VERSION},
        {"help", no_argument, NULL, OPT_HELP},
        {NULL, 0, NULL, 0},
    };
    /* Flags win over everything, so they are applied last: collect them first. */
    struct { const char *key, *value; } flags[32];
    int nflags = 0;
    const char *config = getenv("SHADEBENCH_CONFIG");
    bool config_required = config && *config;
    int c;
    while ((c = getopt_long(argc, argv, "", longopts, NULL)) != -1) {
        const char *key = NULL;
        switch (c) {
        case OPT_LISTEN: key = "listen"; break;
        case OPT_STATE: key = "state-dir"; break;
        case OPT_DEVICE: key = "device"; break;
        case OPT_QUEUE: key = "queue-size"; break;
        case OPT_TOKEN: key = "token"; break;
        case OPT_KEEP_JOBS: key = "keep-jobs"; break;
        case OPT_KEEP_DAYS: key = "keep-days"; break;
        case OPT_JOB_TIMEOUT: key = "job-timeout"; break;
        case OPT_MAX_JOB: key = "max-job-seconds"; break;
        case OPT_MAX_FRAME: key = "max-frame-seconds"; break;
        case OPT_STALL: key = "stall-seconds"; break;
        case OPT_MEMORY: key = "memory-budget"; break;
        case OPT_MAX_CONN: key = "max-connections"; break;
        case OPT_MAX_CONN_IP: key = "max-connections-per-ip"; break;
        case OPT_MAX_ASSET: key = "max-asset-bytes"; break;
        case OPT_ASSET_DIR: key = "asset-dir"; break;
        case OPT_ASSET_CONV: key = "asset-converter"; break;
        case OPT_CHROMIUM: key = "chromium"; break;
        case OPT_REF_VIEWER: key = "reference-viewer"; break;
        case OPT_REF_TIMEOUT: key = "reference-timeout"; break;
        case OPT_REF_MEMORY: key = "reference-memory"; break;
        case OPT_LOG: key = "log-level"; break;
        case OPT_CONFIG: config = optarg; config_required = true; break;
        case OPT_PORT_FILE: o.port_file = optarg; break;
        case OPT_LIST: o.list_devices = true; break;
        case OPT_JSON: o.json = true; break;
        case OPT_ONCE: o.once = optarg; break;
        case OPT_OUT: o.out = optarg; break;
        case OPT_DEBUG: o.gl_debug = true; break;
        case OPT_VERSION: printf("shadebenchd %s\n", PACKAGE_VERSION); return 0;
        case OPT_HELP: usage(stdout); return 0;
        default: usage(stderr); return 2;
        }
        if (key && nflags < 32) {
            flags[nflags].key = key;
            flags[nflags++].value = optarg;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "shadebenchd: unexpected argument %s\n", argv[optind]);
        return 2;
    }
    if (!load_config(&o, config_required ? config : DEFAULT_CONFIG, config_required) ||
        !load_environment(&o))
        return 2;
    for (int i = 0; i < nflags; i++) {
        char origin[32];
        snprintf(origin, sizeof(origin), "--%s", flags[i].key);
        if (!apply_setting(&o, flags[i].key, flags[i].value, origin))
            return 2;
    }
    job_spec_set_default_timeout(o.job_timeout);
    job_spec_set_max_seconds(o.max_job_s);
    job_spec_set_max_frame_seconds(o.max_frame_s);
    if (o.json && !o.list_devices) {
        fprintf(stderr, "shadebenchd: --json goes with --list-devices\n");
        return 2;
    }
    if (o.list_devices)
        return list_devices(o.json);
    if (o.once) {
        if (!o.out) {
            fprintf(stderr, "shadebenchd: --once needs --out DIR\n");
            return 2;
        }
        return run_once(&o, &catalog);
    }
    return serve(&o, &catalog);
}
