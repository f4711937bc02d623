#define _POSIX_C_SOURCE 200809L
#include <getopt.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <epoxy/gl.h>

#include "config.h"
#include "daemon/egl.h"
#include "daemon/fsutil.h"
#include "daemon/http.h"
#include "daemon/job.h"
#include "daemon/log.h"
#include "daemon/queue.h"
#include "daemon/runner.h"
#include "daemon/technique.h"

struct options {
    const char *listen;
    const char *state_dir;
    const char *once;
    const char *out;
    const char *port_file;
    int device;
    int queue_size;
    bool list_devices;
    bool gl_debug;
};

static void usage(FILE *f)
{
    fprintf(f,
            "Usage: shadebenchd [OPTION]...\n"
            "Headless OpenGL benchmark daemon: takes shading jobs over HTTP.\n\n"
            "  --listen HOST:PORT   address to serve (default 127.0.0.1:8460; port 0 = any free)\n"
            "  --state-dir DIR      where job results and frames are kept\n"
            "                       (default $STATE_DIRECTORY, else /var/lib/shadebench)\n"
            "  --device N           use EGL device N (see --list-devices; default: first\n"
            "                       hardware device, then software, then surfaceless)\n"
            "  --queue-size N       jobs that may wait at once (default 64)\n"
            "  --port-file FILE     write the bound port to FILE once listening\n"
            "  --list-devices       print the EGL devices and exit\n"
            "  --once JOB.json      run one job without HTTP, then exit\n"
            "  --out DIR            with --once: where result.json and frames go\n"
            "  --gl-debug           request a debug GL context\n"
            "  --log-level LEVEL    debug, info, warn or error (default info)\n"
            "  --version, --help\n");
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

static int list_devices(void)
{
    struct egl_device_info devs[16];
    char err[256] = "";
    int n = egl_list_devices(devs, 16, err, sizeof(err));
    if (n < 0) {
        printf("no EGL device enumeration: %s\n", err);
        n = 0;
    }
    for (int i = 0; i < n; i++) {
        char why[512] = "";
        const char *renderer = devs[i].renderer;
        char gl_renderer[256] = "";
        /* The GL renderer string is what users recognise: open each device briefly. */
        struct egl_context *ctx = egl_context_create(i, false, why, sizeof(why));
        if (ctx) {
            snprintf(gl_renderer, sizeof(gl_renderer), "%s", (const char *)glGetString(GL_RENDERER));
            renderer = gl_renderer;
            egl_context_destroy(ctx);
        }
        printf("%d: %s%s%s  renderer=%s  drm=%s  render_node=%s%s%s\n", i,
               devs[i].software ? "software" : "hardware", devs[i].driver[0] ? "  driver=" : "",
               devs[i].driver, renderer[0] ? renderer : "?",
               devs[i].drm_node[0] ? devs[i].drm_node : "-",
               devs[i].render_node[0] ? devs[i].render_node : "-",
               ctx ? "" : "  (no GL 4.3 context: ", ctx ? "" : why);
        if (!ctx)
            printf(")\n");
    }
    return 0;
}

static int run_once(const struct options *o)
{
    size_t len = 0;
    char *text = fs_read_file(o->once, JOB_MAX_BODY_BYTES + 1, &len);
    if (!text) {
        fprintf(stderr, "shadebenchd: cannot read %s\n", o->once);
        return 2;
    }
    struct job_spec spec;
    struct job_error jerr;
    bool ok = len <= JOB_MAX_BODY_BYTES &&
              job_spec_parse_text(text, len, technique_names(), &spec, &jerr);
    free(text);
    if (!ok) {
        if (len > JOB_MAX_BODY_BYTES)
            fprintf(stderr, "shadebenchd: %s: the job must be at most 65536 bytes\n", o->once);
        else
            fprintf(stderr, "shadebenchd: %s: %s: %s\n", o->once, jerr.field, jerr.message);
        return 2;
    }
    if (!fs_mkdir_p(o->out)) {
        fprintf(stderr, "shadebenchd: cannot create %s\n", o->out);
        return 2;
    }
    char err[512];
    struct queue *q = queue_create(NULL, 1);
    struct runner *r = q ? runner_create(q, o->device, o->gl_debug, err, sizeof(err)) : NULL;
    if (!r) {
        fprintf(stderr, "shadebenchd: %s\n", q ? err : "out of memory");
        queue_destroy(q);
        return 1;
    }
    char id[24];
    int rc = 1;
    if (queue_submit(q, &spec, o->out, id) == QUEUE_OK) {
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
        json_decref(job);
    } else {
        fprintf(stderr, "shadebenchd: cannot create the job in %s\n", o->out);
    }
    runner_destroy(r);
    queue_destroy(q);
    return rc;
}

static int serve(const struct options *o)
{
    char state_dir[PATH_MAX];
    const char *env = getenv("STATE_DIRECTORY");
    snprintf(state_dir, sizeof(state_dir), "%s",
             o->state_dir ? o->state_dir : (env && *env ? env : "/var/lib/shadebench"));
    if (!fs_mkdir_p(state_dir)) {
        LOG(LOG_ERROR, "cannot create the state directory %s", state_dir);
        return 1;
    }
    /* Signals are taken by sigwait below, never by the render or HTTP threads. */
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, NULL);
    signal(SIGPIPE, SIG_IGN);

    char err[512];
    struct queue *q = queue_create(state_dir, o->queue_size);
    struct runner *r = q ? runner_create(q, o->device, o->gl_debug, err, sizeof(err)) : NULL;
    if (!r) {
        LOG(LOG_ERROR, "%s", q ? err : "out of memory");
        queue_destroy(q);
        return 1;
    }
    struct http_server *http = http_server_create(o->listen, q, r, err, sizeof(err));
    if (!http) {
        LOG(LOG_ERROR, "%s", err);
        runner_destroy(r);
        queue_destroy(q);
        return 1;
    }
    LOG(LOG_INFO, "shadebenchd %s listening on %s (port %d), state in %s", PACKAGE_VERSION,
        o->listen, http_server_port(http), state_dir);
    if (o->port_file) {
        char buf[16];
        int n = snprintf(buf, sizeof(buf), "%d\n", http_server_port(http));
        if (!fs_write_atomic(o->port_file, buf, (size_t)n))
            LOG(LOG_WARN, "cannot write %s", o->port_file);
    }
    int sig = 0;
    sigwait(&set, &sig);
    LOG(LOG_INFO, "signal %d: stopping", sig);
    http_server_destroy(http);
    runner_destroy(r);
    queue_destroy(q);
    return 0;
}

int main(int argc, char **argv)
{
    struct options o = {.listen = "127.0.0.1:8460", .device = -1, .queue_size = 64};
    enum { OPT_LISTEN = 256, OPT_STATE, OPT_DEVICE, OPT_QUEUE, OPT_PORT_FILE, OPT_LIST,
           OPT_ONCE, OPT_OUT, OPT_DEBUG, OPT_LOG, OPT_VERSION, OPT_HELP };
    static const struct option longopts[] = {
        {"listen", required_argument, NULL, OPT_LISTEN},
        {"state-dir", required_argument, NULL, OPT_STATE},
        {"device", required_argument, NULL, OPT_DEVICE},
        {"queue-size", required_argument, NULL, OPT_QUEUE},
        {"port-file", required_argument, NULL, OPT_PORT_FILE},
        {"list-devices", no_argument, NULL, OPT_LIST},
        {"once", required_argument, NULL, OPT_ONCE},
        {"out", required_argument, NULL, OPT_OUT},
        {"gl-debug", no_argument, NULL, OPT_DEBUG},
        {"log-level", required_argument, NULL, OPT_LOG},
        {"version", no_argument, NULL, OPT_VERSION},
        {"help", no_argument, NULL, OPT_HELP},
        {NULL, 0, NULL, 0},
    };
    int c;
    while ((c = getopt_long(argc, argv, "", longopts, NULL)) != -1) {
        switch (c) {
        case OPT_LISTEN: o.listen = optarg; break;
        case OPT_STATE: o.state_dir = optarg; break;
        case OPT_DEVICE:
            if (!parse_int(optarg, 0, 15, &o.device)) {
                fprintf(stderr, "shadebenchd: --device must be an integer from 0 to 15\n");
                return 2;
            }
            break;
        case OPT_QUEUE:
            if (!parse_int(optarg, 1, 100000, &o.queue_size)) {
                fprintf(stderr, "shadebenchd: --queue-size must be an integer from 1 to 100000\n");
                return 2;
            }
            break;
        case OPT_PORT_FILE: o.port_file = optarg; break;
        case OPT_LIST: o.list_devices = true; break;
        case OPT_ONCE: o.once = optarg; break;
        case OPT_OUT: o.out = optarg; break;
        case OPT_DEBUG: o.gl_debug = true; break;
        case OPT_LOG: {
            static const char *const levels[] = {"debug", "info", "warn", "error"};
            int found = -1;
            for (int i = 0; i < 4; i++)
                if (strcmp(optarg, levels[i]) == 0)
                    found = i;
            if (found < 0) {
                fprintf(stderr, "shadebenchd: --log-level must be debug, info, warn or error\n");
                return 2;
            }
            log_set_level((enum log_level)found);
            break;
        }
        case OPT_VERSION: printf("shadebenchd %s\n", PACKAGE_VERSION); return 0;
        case OPT_HELP: usage(stdout); return 0;
        default: usage(stderr); return 2;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "shadebenchd: unexpected argument %s\n", argv[optind]);
        return 2;
    }
    if (o.list_devices)
        return list_devices();
    if (o.once) {
        if (!o.out) {
            fprintf(stderr, "shadebenchd: --once needs --out DIR\n");
            return 2;
        }
        return run_once(&o);
    }
    return serve(&o);
}
