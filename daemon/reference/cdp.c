#include "daemon/reference/cdp.h"

#include <errno.h>
#include <math.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common/clock.h"

struct cdp {
    int wfd, rfd;
    long next_id;
    char *buf;
    size_t len, cap;
    cdp_event_fn on_event;
    void *ctx;
};

struct cdp *cdp_create(int wfd, int rfd, cdp_event_fn on_event, void *ctx)
{
    struct cdp *c = calloc(1, sizeof(*c));
    if (!c) {
        close(wfd);
        close(rfd);
        return NULL;
    }
    c->wfd = wfd;
    c->rfd = rfd;
    c->on_event = on_event;
    c->ctx = ctx;
    return c;
}

void cdp_destroy(struct cdp *c)
{
    if (!c)
        return;
    if (c->wfd >= 0)
        close(c->wfd);
    if (c->rfd >= 0)
        close(c->rfd);
    free(c->buf);
    free(c);
}

static bool write_all(int fd, const char *p, size_t n)
{
    while (n) {
        ssize_t w = write(fd, p, n);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return false;
        p += w;
        n -= (size_t)w;
    }
    return true;
}

long cdp_send(struct cdp *c, const char *session, const char *method, json_t *params, char *err,
              size_t errlen)
{
    long id = ++c->next_id;
    json_t *msg = json_pack("{s:I, s:s, s:o}", "id", (json_int_t)id, "method", method, "params",
                            params ? params : json_object());
    if (msg && session)
        json_object_set_new(msg, "sessionId", json_string(session));
    char *text = msg ? json_dumps(msg, JSON_COMPACT) : NULL;
    json_decref(msg);
    if (!text) {
        snprintf(err, errlen, "out of memory for the DevTools message %s", method);
        return -1;
    }
    bool ok = c->wfd >= 0 && write_all(c->wfd, text, strlen(text) + 1); /* with its NUL */
    free(text);
    if (!ok) {
        snprintf(err, errlen, "Chromium closed its DevTools pipe (sending %s)", method);
        return -1;
    }
    return id;
}

/* The next whole message, waiting until deadline; NULL with err. */
static json_t *next_message(struct cdp *c, double deadline, char *err, size_t errlen)
{
    for (;;) {
        char *nul = c->len ? memchr(c->buf, '\0', c->len) : NULL;
        if (nul) {
            size_t n = (size_t)(nul - c->buf);
            json_error_t je;
            json_t *m = json_loadb(c->buf, n, 0, &je);
            memmove(c->buf, nul + 1, c->len - n - 1);
            c->len -= n + 1;
            if (!m) {
                snprintf(err, errlen, "Chromium sent a DevTools message that is not JSON: %s",
                         je.text);
                return NULL;
            }
            return m;
        }
        double left = deadline - clock_mono_s();
        if (left <= 0) {
            snprintf(err, errlen, "timed out");
            return NULL;
        }
        struct pollfd p = {.fd = c->rfd, .events = POLLIN};
        int r = poll(&p, 1, (int)fmin(left * 1000.0 + 1, 1000.0));
        if (r < 0 && errno != EINTR) {
            snprintf(err, errlen, "poll: %s", strerror(errno));
            return NULL;
        }
        if (r <= 0)
            continue;
        if (c->cap - c->len < (1u << 16)) {
            size_t cap = c->cap ? c->cap * 2 : (1u << 20);
            if (cap > CDP_MAX_MESSAGE + (1u << 16)) {
                snprintf(err, errlen, "a DevTools message over %u MiB", CDP_MAX_MESSAGE >> 20);
                return NULL;
            }
            char *b = realloc(c->buf, cap);
            if (!b) {
                snprintf(err, errlen, "out of memory reading from Chromium");
                return NULL;
            }
            c->buf = b;
            c->cap = cap;
        }
        ssize_t n = read(c->rfd, c->buf + c->len, c->cap - c->len);
        if (n < 0 && (errno == EINTR || errno == EAGAIN))
            continue;
        if (n <= 0) {
            snprintf(err, errlen, "Chromium closed its DevTools pipe (it exited or crashed)");
            return NULL;
        }
        c->len += (size_t)n;
    }
}

json_t *cdp_call(struct cdp *c, const char *session, const char *method, json_t *params,
                 double deadline, char *err, size_t errlen)
{
    long id = cdp_send(c, session, method, params, err, errlen);
    if (id < 0)
        return NULL;
    for (;;) {
        char why[256];
        json_t *m = next_message(c, deadline, why, sizeof(why));
        if (!m) {
            snprintf(err, errlen, "%s: %s", method, why);
            return NULL;
        }
        json_t *mid = json_object_get(m, "id");
        if (mid && json_integer_value(mid) == id) {
            json_t *e = json_object_get(m, "error");
            if (e) {
                snprintf(err, errlen, "%s: %s", method,
                         json_string_value(json_object_get(e, "message"))
                             ? json_string_value(json_object_get(e, "message"))
                             : "refused");
                json_decref(m);
                return NULL;
            }
            json_t *r = json_incref(json_object_get(m, "result"));
            json_decref(m);
            return r ? r : json_object();
        }
        const char *ev = json_string_value(json_object_get(m, "method"));
        if (ev && c->on_event)
            c->on_event(c->ctx, c, ev, json_object_get(m, "params"),
                        json_string_value(json_object_get(m, "sessionId")));
        json_decref(m);
    }
}
