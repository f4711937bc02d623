#define _GNU_SOURCE /* mkdtemp, pipe2, execvpe */
/* shadebench-reference: the independent glTF reference renderer, a child
 * process of the daemon (daemon/jobs/fidelity.c runs it; docs/assets.md,
 * "The Khronos reference"). It starts headless Chromium (WebGL 2 in
 * software, SwiftShader) with the DevTools protocol on a pipe, serves it the
 * page (page.html, page.js), the Khronos glTF Sample Viewer vendored by
 * tools/setup, the asset and the environment from files (the Fetch domain:
 * no port, no network; any other URL is answered 404), and has the viewer
 * draw the asset lit and in its debug channels with the job's camera,
 * lights, environment, exposure and tone curve.
 *
 *   shadebench-reference render REQUEST.json
 *
 * REQUEST.json (written by the daemon): chromium, page_dir, viewer_dir,
 * asset, environment (or null), out_dir, timeout_s, ibl_sampler, and
 * render, the page's request (page.js: sbRender). Each channel is written
 * to out_dir/NAME.png. Exit 0: stdout one JSON object, what each step cost
 * (chromium_start_ms, page_ms, load_ms, environment_ms, per channel
 * render_ms, total_ms) and the browser's and WebGL's strings. Exit 2:
 * stdout {"error": "..."}, what went wrong (Chromium would not start, the
 * viewer failed, the time ran out). Chromium runs in this process's group:
 * the daemon kills the group. One thread. */
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "common/clock.h"
#include "common/fsutil.h"
#include "common/png_io.h"
#include "daemon/reference/cdp.h"
#include "daemon/reference/reference_files.h"

#define ORIGIN "http://shadebench.invalid/"

struct ctx {
    const char *page_dir, *viewer_dir, *asset, *environment;
    char *viewer_module; /* the module with the IBL sampler's sizes set */
    size_t viewer_module_len;
    char *session;
    char last_exception[1024];
    char missing[512]; /* the first file the page asked for that is not there */
};

static int fail(const char *fmt, ...)
{
    char msg[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    json_t *o = json_pack("{s:s}", "error", msg);
    char *s = o ? json_dumps(o, JSON_COMPACT) : NULL;
    json_decref(o);
    if (s)
        printf("%s\n", s);
    free(s);
    fflush(stdout);
    return 2;
}

static char *b64_encode(const unsigned char *p, size_t n)
{
    static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char *out = malloc((n + 2) / 3 * 4 + 1), *o = out;
    if (!out)
        return NULL;
    for (size_t i = 0; i < n; i += 3) {
        unsigned v = (unsigned)p[i] << 16 | (i + 1 < n ? (unsigned)p[i + 1] << 8 : 0) |
                     (i + 2 < n ? p[i + 2] : 0);
        *o++ = tab[v >> 18 & 63];
        *o++ = tab[v >> 12 & 63];
        *o++ = i + 1 < n ? tab[v >> 6 & 63] : '=';
        *o++ = i + 2 < n ? tab[v & 63] : '=';
    }
    *o = '\0';
    return out;
}

static unsigned char *b64_decode(const char *s, size_t *n)
{
    size_t len = strlen(s);
    unsigned char *out = malloc(len / 4 * 3 + 3);
    if (!out)
        return NULL;
    size_t k = 0;
    unsigned v = 0;
    int bits = 0;
    for (size_t i = 0; i < len; i++) {
        int c = s[i], d;
        if (c >= 'A' && c <= 'Z') d = c - 'A';
        else if (c >= 'a' && c <= 'z') d = c - 'a' + 26;
        else if (c >= '0' && c <= '9') d = c - '0' + 52;
        else if (c == '+') d = 62;
        else if (c == '/') d = 63;
        else if (c == '=') break;
        else continue;
        v = v << 6 | (unsigned)d;
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out[k++] = (unsigned char)(v >> bits & 0xff);
        }
    }
    *n = k;
    return out;
}

/* What the page may fetch: the page, the viewer, the asset, the environment. */
static bool resolve(struct ctx *x, const char *url, char *path, size_t cap, const char **type,
                    bool *module)
{
    *module = false;
    if (strncmp(url, ORIGIN, strlen(ORIGIN)) != 0)
        return false;
    const char *p = url + strlen(ORIGIN);
    if (strchr(p, '?') || strstr(p, ".."))
        return false;
    *type = "application/octet-stream";
    if (strcmp(p, "page.html") == 0 || strcmp(p, "page.js") == 0) {
        snprintf(path, cap, "%s/%s", x->page_dir, p);
        *type = p[5] == 'h' ? "text/html" : "text/javascript";
        return true;
    }
    if (strcmp(p, "viewer/" REFERENCE_VIEWER_MODULE) == 0) {
        *module = true;
        *type = "text/javascript";
        return true;
    }
    if (strncmp(p, "viewer/libs/", 12) == 0 && !strchr(p + 12, '/')) {
        snprintf(path, cap, "%s/libs/%s", x->viewer_dir, p + 12);
        size_t n = strlen(p);
        *type = n > 5 && strcmp(p + n - 5, ".wasm") == 0 ? "application/wasm" : "text/javascript";
        return true;
    }
    if (strcmp(p, "asset.glb") == 0 || strcmp(p, "asset.gltf") == 0) {
        snprintf(path, cap, "%s", x->asset);
        return true;
    }
    if (strcmp(p, "environment.hdr") == 0 && x->environment) {
        snprintf(path, cap, "%s", x->environment);
        return true;
    }
    return false;
}

static void serve(struct ctx *x, struct cdp *c, json_t *params, const char *session)
{
    const char *rid = json_string_value(json_object_get(params, "requestId"));
    const char *url = json_string_value(json_object_get(json_object_get(params, "request"), "url"));
    char path[4096], err[256];
    const char *type = NULL;
    bool module = false;
    char *body = NULL;
    size_t len = 0;
    bool found = rid && url && resolve(x, url, path, sizeof(path), &type, &module);
    if (found && module) {
        body = b64_encode((const unsigned char *)x->viewer_module, x->viewer_module_len);
    } else if (found) {
        char *data = fs_read_file(path, REFERENCE_MAX_SERVED_BYTES, &len);
        if (data)
            body = b64_encode((const unsigned char *)data, len);
        else if (!x->missing[0])
            snprintf(x->missing, sizeof(x->missing), "%.400s (%s)", path, strerror(errno));
        free(data);
    }
    if (!rid)
        return;
    json_t *p = body ? json_pack("{s:s, s:i, s:[{s:s, s:s}], s:s}", "requestId", rid,
                                 "responseCode", 200, "responseHeaders", "name", "Content-Type",
                                 "value", type, "body", body)
                     : json_pack("{s:s, s:i, s:s}", "requestId", rid, "responseCode", 404,
                                 "body", "");
    free(body);
    if (!body && url && strstr(url, "favicon") == NULL && !x->missing[0])
        snprintf(x->missing, sizeof(x->missing), "%s (not served)", url);
    cdp_send(c, session, "Fetch.fulfillRequest", p, err, sizeof(err));
}

static void on_event(void *ctx, struct cdp *c, const char *method, json_t *params,
                     const char *session)
{
    struct ctx *x = ctx;
    if (strcmp(method, "Fetch.requestPaused") == 0)
        serve(x, c, params, session);
    else if (strcmp(method, "Runtime.exceptionThrown") == 0) {
        json_t *d = json_object_get(params, "exceptionDetails");
        const char *text = json_string_value(
            json_object_get(json_object_get(d, "exception"), "description"));
        snprintf(x->last_exception, sizeof(x->last_exception), "%s",
                 text ? text : json_string_value(json_object_get(d, "text")) ?
                                json_string_value(json_object_get(d, "text")) : "an exception");
    }
}

/* The viewer's module with its IBL sampler's sizes replaced (the 1.1.0
 * defaults take minutes in software: reference_files.h). */
static bool load_module(struct ctx *x, const json_t *sampler, char *err, size_t errlen)
{
    char path[4096];
    snprintf(path, sizeof(path), "%s/%s", x->viewer_dir, REFERENCE_VIEWER_MODULE);
    size_t len;
    char *src = fs_read_file(path, REFERENCE_MAX_SERVED_BYTES, &len);
    if (!src) {
        snprintf(err, errlen, "the Khronos viewer is not installed: %.1000s: %s (tools/setup "
                 "vendors it)", path, strerror(errno));
        return false;
    }
    struct reference_sampler s;
    reference_sampler_from_json(sampler, &s);
    char *patched = reference_patch_viewer(src, len, &s, &x->viewer_module_len, err, errlen);
    free(src);
    if (!patched)
        return false;
    x->viewer_module = patched;
    return true;
}

static pid_t start_chromium(const char *chromium, const char *profile, int *wfd, int *rfd,
                            char *err, size_t errlen)
{
    int to_browser[2], from_browser[2];
    if (pipe2(to_browser, O_CLOEXEC) != 0 || pipe2(from_browser, O_CLOEXEC) != 0) {
        snprintf(err, errlen, "pipe: %s", strerror(errno));
        return -1;
    }
    char user_data[4200];
    snprintf(user_data, sizeof(user_data), "--user-data-dir=%s", profile);
    const char *argv[32];
    int n = 0;
    argv[n++] = chromium;
    argv[n++] = "--headless=new";
    if (geteuid() == 0)
        argv[n++] = "--no-sandbox"; /* Chromium refuses to run as root with its sandbox */
    argv[n++] = "--remote-debugging-pipe";
    argv[n++] = user_data;
    argv[n++] = "--use-angle=swiftshader";
    argv[n++] = "--enable-unsafe-swiftshader";
    argv[n++] = "--no-first-run";
    argv[n++] = "--no-default-browser-check";
    argv[n++] = "--disable-background-networking";
    argv[n++] = "--disable-component-update";
    argv[n++] = "--disable-extensions";
    argv[n++] = "--disable-sync";
    argv[n++] = "--disable-default-apps";
    argv[n++] = "--mute-audio";
    argv[n++] = "--host-resolver-rules=MAP * ~NOTFOUND";
    argv[n++] = "about:blank";
    argv[n] = NULL;
    pid_t pid = fork();
    if (pid < 0) {
        snprintf(err, errlen, "fork: %s", strerror(errno));
        return -1;
    }
    if (pid == 0) {
        /* fd 3: the browser reads; fd 4: it writes. dup2 clears CLOEXEC. */
        int r = dup(to_browser[0]), w = dup(from_browser[1]);
        if (r < 0 || w < 0 || dup2(r, 3) < 0 || dup2(w, 4) < 0)
            _exit(127);
        int devnull = open("/dev/null", O_RDWR);
        if (devnull >= 0) {
            dup2(devnull, 0);
            dup2(devnull, 1); /* stdout is our answer to the daemon */
        }
        execv(chromium, (char *const *)argv);
        _exit(127);
    }
    close(to_browser[0]);
    close(from_browser[1]);
    *wfd = to_browser[1];
    *rfd = from_browser[0];
    return pid;
}

static void remove_tree(const char *dir)
{
    pid_t pid = fork();
    if (pid == 0) {
        execl("/bin/rm", "rm", "-rf", "--", dir, (char *)NULL);
        _exit(127);
    }
    if (pid > 0)
        waitpid(pid, NULL, 0);
}

int main(int argc, char **argv)
{
    if (argc != 3 || strcmp(argv[1], "render") != 0) {
        fprintf(stderr, "usage: shadebench-reference render REQUEST.json\n");
        return 1;
    }
    double t0 = clock_mono_s();
    json_error_t je;
    json_t *req = json_load_file(argv[2], 0, &je);
    if (!req)
        return fail("%s: %s", argv[2], je.text);
    struct ctx x = {
        .page_dir = json_string_value(json_object_get(req, "page_dir")),
        .viewer_dir = json_string_value(json_object_get(req, "viewer_dir")),
        .asset = json_string_value(json_object_get(req, "asset")),
        .environment = json_string_value(json_object_get(req, "environment")),
    };
    const char *chromium = json_string_value(json_object_get(req, "chromium"));
    const char *out_dir = json_string_value(json_object_get(req, "out_dir"));
    json_t *render = json_object_get(req, "render");
    double timeout = json_number_value(json_object_get(req, "timeout_s"));
    if (!x.page_dir || !x.viewer_dir || !x.asset || !chromium || !out_dir ||
        !json_is_object(render))
        return fail("%s: needs chromium, page_dir, viewer_dir, asset, out_dir and render",
                    argv[2]);
    double deadline = t0 + (timeout > 0 ? timeout : 300);
    char err[2048];
    if (!load_module(&x, json_object_get(req, "ibl_sampler"), err, sizeof(err)))
        return fail("%s", err);
    size_t alen = strlen(x.asset);
    bool gltf = alen > 5 && strcmp(x.asset + alen - 5, ".gltf") == 0;
    json_object_set_new(render, "asset", json_string(gltf ? "asset.gltf" : "asset.glb"));
    if (x.environment)
        json_object_set_new(render, "environment_url", json_string("environment.hdr"));

    char profile[] = "/tmp/shadebench-reference-XXXXXX";
    if (!mkdtemp(profile))
        return fail("mkdtemp %s: %s", profile, strerror(errno));
    int wfd = -1, rfd = -1, rc = 2;
    json_t *answer = NULL, *r = NULL;
    struct cdp *c = NULL;
    pid_t pid = start_chromium(chromium, profile, &wfd, &rfd, err, sizeof(err));
    if (pid < 0) {
        rc = fail("cannot start Chromium %s: %s", chromium, err);
        goto out;
    }
    c = cdp_create(wfd, rfd, on_event, &x);
    if (!c) {
        rc = fail("out of memory");
        goto out;
    }
    json_t *version = cdp_call(c, NULL, "Browser.getVersion", NULL, t0 + 60, err, sizeof(err));
    if (!version) {
        rc = fail("Chromium %s did not start (%s); is it Chromium, and does it run here?",
                  chromium, err);
        goto out;
    }
    double t_started = clock_mono_s();
    json_t *target = cdp_call(c, NULL, "Target.createTarget",
                              json_pack("{s:s}", "url", "about:blank"), deadline, err, sizeof(err));
    const char *tid = json_string_value(json_object_get(target, "targetId"));
    json_t *att = tid ? cdp_call(c, NULL, "Target.attachToTarget",
                                 json_pack("{s:s, s:b}", "targetId", tid, "flatten", 1), deadline,
                                 err, sizeof(err))
                      : NULL;
    json_decref(target);
    x.session = att ? strdup(json_string_value(json_object_get(att, "sessionId")) ?
                                 json_string_value(json_object_get(att, "sessionId")) : "")
                    : NULL;
    json_decref(att);
    if (!x.session) {
        rc = fail("Chromium would not open a page: %s", err);
        goto version_out;
    }
    json_t *ok;
    if (!(ok = cdp_call(c, x.session, "Fetch.enable",
                        json_pack("{s:[{s:s}]}", "patterns", "urlPattern", "*"), deadline, err,
                        sizeof(err))) ||
        (json_decref(ok), !(ok = cdp_call(c, x.session, "Runtime.enable", NULL, deadline, err,
                                          sizeof(err)))) ||
        (json_decref(ok), !(ok = cdp_call(c, x.session, "Page.navigate",
                                          json_pack("{s:s}", "url", ORIGIN "page.html"), deadline,
                                          err, sizeof(err))))) {
        rc = fail("the page: %s", err);
        goto version_out;
    }
    json_decref(ok);
    /* The module loaded once window.sbReady is set. */
    for (;;) {
        json_t *v = cdp_call(c, x.session, "Runtime.evaluate",
                             json_pack("{s:s, s:b}", "expression", "window.sbReady === true",
                                       "returnByValue", 1),
                             deadline, err, sizeof(err));
        bool ready = json_is_true(json_object_get(json_object_get(v, "result"), "value"));
        json_decref(v);
        if (ready)
            break;
        if (!v || x.missing[0] || x.last_exception[0] || clock_mono_s() > deadline) {
            rc = fail("the viewer's page did not load: %s",
                      x.missing[0] ? x.missing : x.last_exception[0] ? x.last_exception
                      : v ? "timed out" : err);
            goto version_out;
        }
        usleep(20000);
    }
    double t_page = clock_mono_s();
    char *text = json_dumps(render, JSON_COMPACT);
    size_t need = text ? strlen(text) + 32 : 0;
    char *expr = text ? malloc(need) : NULL;
    if (!expr) {
        free(text);
        rc = fail("out of memory");
        goto version_out;
    }
    snprintf(expr, need, "sbRender(%s)", text);
    free(text);
    r = cdp_call(c, x.session, "Runtime.evaluate",
                 json_pack("{s:s, s:b, s:b}", "expression", expr, "awaitPromise", 1,
                           "returnByValue", 1),
                 deadline, err, sizeof(err));
    free(expr);
    if (!r) {
        rc = fail("the viewer's render: %s", strcmp(err, "Runtime.evaluate: timed out") == 0
                                                 ? "timed out" : err);
        goto version_out;
    }
    json_t *exc = json_object_get(r, "exceptionDetails");
    if (exc) {
        const char *d = json_string_value(
            json_object_get(json_object_get(exc, "exception"), "description"));
        rc = fail("the viewer failed: %s", d ? d : json_string_value(json_object_get(exc, "text")));
        goto version_out;
    }
    json_t *val = json_object_get(json_object_get(r, "result"), "value");
    json_t *chans = json_object_get(val, "channels");
    int w = (int)json_integer_value(json_object_get(render, "width"));
    int h = (int)json_integer_value(json_object_get(render, "height"));
    answer = json_pack("{s:f, s:f, s:f, s:f, s:[], s:s?, s:s?, s:s?}", "chromium_start_ms",
                       (t_started - t0) * 1000.0, "page_ms", (t_page - t_started) * 1000.0,
                       "load_ms", json_number_value(json_object_get(val, "load_ms")),
                       "environment_ms", json_number_value(json_object_get(val, "environment_ms")),
                       "channels", "browser",
                       json_string_value(json_object_get(version, "product")), "webgl_renderer",
                       json_string_value(json_object_get(val, "renderer")), "webgl_version",
                       json_string_value(json_object_get(val, "version")));
    if (answer) {
        /* What the page changed in the file for the viewer (page.js:
         * restateMirroredMatrices) and in the viewer itself (its
         * viewer_patches), and its rasteriser's precision. */
        json_t *restated = json_object_get(val, "mirrored_matrices_restated");
        json_object_set_new(answer, "mirrored_matrices_restated",
                            json_is_array(restated) ? json_incref(restated) : json_array());
        json_t *patches = json_object_get(val, "viewer_patches");
        json_object_set_new(answer, "viewer_patches",
                            json_is_array(patches) ? json_incref(patches) : json_array());
        json_t *bits = json_object_get(val, "subpixel_bits");
        if (json_is_integer(bits))
            json_object_set(answer, "subpixel_bits", bits);
    }
    size_t i;
    json_t *ch;
    json_array_foreach(chans, i, ch) {
        const char *name = json_string_value(json_object_get(ch, "name"));
        const char *b64 = json_string_value(json_object_get(ch, "rgba"));
        size_t n = 0;
        unsigned char *px = b64 ? b64_decode(b64, &n) : NULL;
        if (!name || !px || n != (size_t)w * (size_t)h * 4) {
            free(px);
            rc = fail("the viewer answered channel %s with %zu bytes, not %dx%d RGBA",
                      name ? name : "?", n, w, h);
            goto version_out;
        }
        char path[4300];
        snprintf(path, sizeof(path), "%s/%s.png", out_dir, name);
        bool wrote = png_write_gl_rgba(path, px, w, h, err, sizeof(err));
        free(px);
        if (!wrote) {
            rc = fail("%s: %s", path, err);
            goto version_out;
        }
        json_array_append_new(json_object_get(answer, "channels"),
                              json_pack("{s:s, s:f}", "name", name, "render_ms",
                                        json_number_value(json_object_get(ch, "render_ms"))));
    }
    json_object_set_new(answer, "total_ms", json_real((clock_mono_s() - t0) * 1000.0));
    char *s = json_dumps(answer, JSON_COMPACT);
    if (s)
        printf("%s\n", s);
    free(s);
    rc = fflush(stdout) == 0 && s ? 0 : 1;
version_out:
    json_decref(version);
out:
    json_decref(r);
    json_decref(answer);
    cdp_destroy(c);
    if (pid > 0) {
        kill(pid, SIGTERM);
        double until = clock_mono_s() + 5;
        int st;
        while (waitpid(pid, &st, WNOHANG) == 0) {
            if (clock_mono_s() > until) {
                kill(pid, SIGKILL);
                waitpid(pid, &st, 0);
                break;
            }
            usleep(20000);
        }
    }
    remove_tree(profile);
    free(x.viewer_module);
    free(x.session);
    json_decref(req);
    return rc;
}
