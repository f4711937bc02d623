#define _GNU_SOURCE /* EPOLLRDHUP */
#include "daemon/api/connections.h"

#include <errno.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "common/clock.h"
#include "common/log.h"

/* The watcher looks at deadlines and sweeps this often; job waits end as
 * soon as the store says something changed. */
enum { TICK_MS = 250 };

enum conn_state {
    K_HEADERS,   /* waiting for a request's headers */
    K_BODY,      /* headers in, reading the body */
    K_ANSWERING, /* the answer is being sent */
    K_WAITING,   /* suspended long-poll */
    K_CUT,       /* shut down for being late; libmicrohttpd closes it */
};

struct conn {
    struct conn *prev, *next;
    struct MHD_Connection *mhd;
    int fd;
    struct sockaddr_storage addr; /* the client's; family 0 when unknown */
    bool reserve;                 /* past its address's per-IP limit */
    uint64_t serial; /* epoll's key: a freed conn is never looked up by pointer */
    enum conn_state state;
    double deadline; /* K_HEADERS and K_BODY, monotonic seconds */
    enum wait_kind kind;
    char id[32];
    double wait_until;
    enum wake wake;
    bool stopping_answer;
    unsigned status;
    /* An upload holding a slot (connections_upload_begin) until its answer
     * is sent: the bytes of its current rate window. */
    bool upload;
    double window_start;
    uint64_t window_bytes;
};

struct connections {
    pthread_mutex_t lock;
    pthread_cond_t drained;
    struct conn *head;
    uint64_t next_serial;
    size_t open, waiting, stopping_answers;
    bool stopping, quit;
    int epfd, evfd;
    pthread_t thread;
    bool thread_started;
    wait_done_fn done;
    void *ctx;
    struct connections_config cfg;
    unsigned long long header_timeouts, body_timeouts, waits_gone, slow_uploads;
};

static void resume_locked(struct connections *cs, struct conn *k, enum wake why)
{
    epoll_ctl(cs->epfd, EPOLL_CTL_DEL, k->fd, NULL);
    k->wake = why;
    k->state = K_ANSWERING;
    cs->waiting--;
    if (why == WAKE_STOPPING) {
        k->stopping_answer = true;
        cs->stopping_answers++;
    }
    MHD_resume_connection(k->mhd);
}

/* Results of done() within one pass, so that many waits on one job cost one
 * look-up. */
struct done_cache {
    struct {
        enum wait_kind kind;
        const char *id;
        bool done;
    } *items;
    size_t n, cap;
};

static bool cached_done(struct connections *cs, struct done_cache *c, enum wait_kind kind,
                        const char *id)
{
    for (size_t i = 0; i < c->n; i++)
        if (c->items[i].kind == kind && strcmp(c->items[i].id, id) == 0)
            return c->items[i].done;
    bool done = cs->done(cs->ctx, kind, id);
    if (c->n == c->cap) {
        size_t cap = c->cap ? c->cap * 2 : 16;
        void *grown = realloc(c->items, cap * sizeof(*c->items));
        if (!grown)
            return done;
        c->items = grown;
        c->cap = cap;
    }
    c->items[c->n].kind = kind;
    c->items[c->n].id = id;
    c->items[c->n++].done = done;
    return done;
}

/* One pass over every connection; returns the next instant a wait ends. */
static double check_locked(struct connections *cs, double now, bool jobs_changed, bool sweep_tick)
{
    struct done_cache cache = {0};
    double next = now + TICK_MS / 1000.0;
    for (struct conn *k = cs->head; k; k = k->next) {
        switch (k->state) {
        case K_HEADERS:
        case K_BODY:
            /* An upload below the minimum rate over its window: cut, so
             * that a slow client gives its slot back (the rest of its body
             * would take hours at its pace). */
            if (k->state == K_BODY && k->upload &&
                now - k->window_start >= cs->cfg.upload_window_s) {
                double need = cs->cfg.upload_min_rate * (now - k->window_start);
                if ((double)k->window_bytes < need) {
                    LOG(LOG_INFO, "an upload brought %llu bytes in %.1f s, less than the %.0f "
                        "bytes a second an upload must keep up: its connection is closed",
                        (unsigned long long)k->window_bytes, now - k->window_start,
                        cs->cfg.upload_min_rate);
                    shutdown(k->fd, SHUT_RDWR);
                    cs->slow_uploads++;
                    k->state = K_CUT;
                    k->upload = false;
                    break;
                }
                k->window_start = now;
                k->window_bytes = 0;
            }
            if (now >= k->deadline) {
                /* The socket stays open until libmicrohttpd closes it (after
                 * CLOSED, which takes this lock): shutting it down makes its
                 * next read fail, so the connection goes at once. */
                shutdown(k->fd, SHUT_RDWR);
                if (k->state == K_HEADERS)
                    cs->header_timeouts++;
                else
                    cs->body_timeouts++;
                k->state = K_CUT;
            }
            break;
        case K_WAITING:
            if (cs->stopping)
                resume_locked(cs, k, WAKE_STOPPING);
            else if (now >= k->wait_until)
                resume_locked(cs, k, WAKE_TIMEOUT);
            else if ((((k->kind == WAIT_JOB || k->kind == WAIT_ASSET) && jobs_changed) ||
                      (k->kind == WAIT_SWEEP && sweep_tick)) &&
                     cached_done(cs, &cache, k->kind, k->id))
                resume_locked(cs, k, WAKE_READY);
            else if (k->wait_until < next)
                next = k->wait_until;
            break;
        default:
            break;
        }
    }
    free(cache.items);
    return next;
}

static void *watcher_main(void *arg)
{
    pthread_setname_np(pthread_self(), "sb-watcher"); /* named in crash reports, top, gdb */
    struct connections *cs = arg;
    struct epoll_event ev[64];
    double next = clock_mono_s(), last_sweep_check = 0;
    for (;;) {
        double now = clock_mono_s();
        int timeout = (int)((next - now) * 1000.0) + 1;
        if (timeout > TICK_MS)
            timeout = TICK_MS;
        if (timeout < 0)
            timeout = 0;
        int n = epoll_wait(cs->epfd, ev, 64, timeout);
        bool poked = false;
        pthread_mutex_lock(&cs->lock);
        if (cs->quit) {
            pthread_mutex_unlock(&cs->lock);
            break;
        }
        for (int i = 0; i < n; i++) {
            if (ev[i].data.u64 == 0) {
                uint64_t count;
                while (read(cs->evfd, &count, sizeof(count)) > 0)
                    ;
                poked = true;
                continue;
            }
            /* The client of a suspended request hung up: end its wait now
             * rather than hold the slot until the wait runs out. */
            for (struct conn *k = cs->head; k; k = k->next)
                if (k->serial == ev[i].data.u64) {
                    if (k->state == K_WAITING) {
                        cs->waits_gone++;
                        resume_locked(cs, k, WAKE_GONE);
                    }
                    break;
                }
        }
        now = clock_mono_s();
        bool sweep_tick = now - last_sweep_check >= TICK_MS / 1000.0 || poked;
        if (sweep_tick)
            last_sweep_check = now;
        next = check_locked(cs, now, poked, sweep_tick);
        if (cs->waiting == 0 && cs->stopping_answers == 0)
            pthread_cond_broadcast(&cs->drained);
        pthread_mutex_unlock(&cs->lock);
    }
    return NULL;
}

struct connections *connections_create(const struct connections_config *cfg, wait_done_fn done,
                                       void *ctx, char *err, size_t errlen)
{
    struct connections *cs = calloc(1, sizeof(*cs));
    if (!cs) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    cs->cfg = *cfg;
    if (cs->cfg.upload_min_rate <= 0)
        cs->cfg.upload_min_rate = CONNECTIONS_UPLOAD_MIN_RATE;
    if (cs->cfg.upload_window_s <= 0)
        cs->cfg.upload_window_s = CONNECTIONS_UPLOAD_WINDOW_S;
    cs->done = done;
    cs->ctx = ctx;
    cs->next_serial = 1; /* 0 is the eventfd's key */
    cs->epfd = epoll_create1(EPOLL_CLOEXEC);
    cs->evfd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    pthread_mutex_init(&cs->lock, NULL);
    pthread_condattr_t attr;
    pthread_condattr_init(&attr);
    pthread_condattr_setclock(&attr, CLOCK_MONOTONIC);
    pthread_cond_init(&cs->drained, &attr);
    pthread_condattr_destroy(&attr);
    struct epoll_event ev = {.events = EPOLLIN, .data.u64 = 0};
    if (cs->epfd < 0 || cs->evfd < 0 || epoll_ctl(cs->epfd, EPOLL_CTL_ADD, cs->evfd, &ev) != 0) {
        snprintf(err, errlen, "cannot set up the connection watcher: %s", strerror(errno));
        goto fail;
    }
    if (pthread_create(&cs->thread, NULL, watcher_main, cs) != 0) {
        snprintf(err, errlen, "cannot start the connection watcher thread");
        goto fail;
    }
    cs->thread_started = true;
    return cs;
fail:
    connections_destroy(cs);
    return NULL;
}

void connections_destroy(struct connections *cs)
{
    if (!cs)
        return;
    if (cs->thread_started) {
        pthread_mutex_lock(&cs->lock);
        cs->quit = true;
        pthread_mutex_unlock(&cs->lock);
        connections_poke(cs);
        pthread_join(cs->thread, NULL);
    }
    while (cs->head) {
        struct conn *k = cs->head;
        cs->head = k->next;
        free(k);
    }
    if (cs->epfd >= 0)
        close(cs->epfd);
    if (cs->evfd >= 0)
        close(cs->evfd);
    pthread_cond_destroy(&cs->drained);
    pthread_mutex_destroy(&cs->lock);
    free(cs);
}

/* The same client address (the port aside)? */
static bool same_address(const struct sockaddr_storage *a, const struct sockaddr_storage *b)
{
    if (a->ss_family != b->ss_family)
        return false;
    if (a->ss_family == AF_INET)
        return memcmp(&((const struct sockaddr_in *)a)->sin_addr,
                      &((const struct sockaddr_in *)b)->sin_addr, sizeof(struct in_addr)) == 0;
    if (a->ss_family == AF_INET6)
        return memcmp(&((const struct sockaddr_in6 *)a)->sin6_addr,
                      &((const struct sockaddr_in6 *)b)->sin6_addr, sizeof(struct in6_addr)) == 0;
    return false;
}

/* Under the lock: does k's address already have its per-IP connections? */
static bool over_per_ip_locked(struct connections *cs, const struct conn *k)
{
    if (!cs->cfg.per_ip || !k->addr.ss_family)
        return false;
    unsigned n = 0;
    for (const struct conn *o = cs->head; o; o = o->next)
        if (same_address(&o->addr, &k->addr) && ++n >= cs->cfg.per_ip)
            return true;
    return false;
}

void connections_notify(void *cls, struct MHD_Connection *c, void **socket_context,
                        enum MHD_ConnectionNotificationCode code)
{
    struct connections *cs = cls;
    if (code == MHD_CONNECTION_NOTIFY_STARTED) {
        const union MHD_ConnectionInfo *info =
            MHD_get_connection_info(c, MHD_CONNECTION_INFO_CONNECTION_FD);
        struct conn *k = info ? calloc(1, sizeof(*k)) : NULL;
        *socket_context = k;
        if (!k)
            return;
        k->mhd = c;
        k->fd = info->connect_fd;
        const union MHD_ConnectionInfo *peer =
            MHD_get_connection_info(c, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
        if (peer && peer->client_addr) {
            size_t len = peer->client_addr->sa_family == AF_INET6 ? sizeof(struct sockaddr_in6)
                         : peer->client_addr->sa_family == AF_INET ? sizeof(struct sockaddr_in)
                                                                   : 0;
            memcpy(&k->addr, peer->client_addr, len);
        }
        k->state = K_HEADERS;
        pthread_mutex_lock(&cs->lock);
        k->reserve = over_per_ip_locked(cs, k);
        /* A reserve connection is for a health checker, which sends its
         * request at once: one that does not gives its slot back soon. */
        double header_s = cs->cfg.header_s;
        if (k->reserve && header_s > CONNECTIONS_RESERVE_HEADER_S)
            header_s = CONNECTIONS_RESERVE_HEADER_S;
        k->deadline = clock_mono_s() + header_s;
        k->serial = cs->next_serial++;
        k->next = cs->head;
        if (cs->head)
            cs->head->prev = k;
        cs->head = k;
        cs->open++;
        pthread_mutex_unlock(&cs->lock);
        return;
    }
    struct conn *k = *socket_context;
    if (!k)
        return;
    pthread_mutex_lock(&cs->lock);
    if (k->state == K_WAITING) {
        epoll_ctl(cs->epfd, EPOLL_CTL_DEL, k->fd, NULL);
        cs->waiting--;
    }
    if (k->stopping_answer)
        cs->stopping_answers--;
    if (k->prev)
        k->prev->next = k->next;
    else
        cs->head = k->next;
    if (k->next)
        k->next->prev = k->prev;
    cs->open--;
    if (cs->waiting == 0 && cs->stopping_answers == 0)
        pthread_cond_broadcast(&cs->drained);
    pthread_mutex_unlock(&cs->lock);
    free(k);
    *socket_context = NULL;
}

struct conn *connections_of(struct MHD_Connection *c)
{
    const union MHD_ConnectionInfo *info =
        MHD_get_connection_info(c, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
    return info ? info->socket_context : NULL;
}

void connections_body_deadline(struct connections *cs, struct conn *k, double seconds)
{
    if (!k)
        return;
    pthread_mutex_lock(&cs->lock);
    if (k->state == K_BODY && seconds > cs->cfg.body_s)
        k->deadline = clock_mono_s() + seconds;
    pthread_mutex_unlock(&cs->lock);
}

void connections_headers_in(struct connections *cs, struct conn *k)
{
    if (!k)
        return;
    pthread_mutex_lock(&cs->lock);
    if (k->state == K_HEADERS) {
        k->state = K_BODY;
        k->deadline = clock_mono_s() + cs->cfg.body_s;
    }
    k->status = 0;
    pthread_mutex_unlock(&cs->lock);
}

/* Under the lock: the soonest an upload of address addr (NULL: any) is
 * judged again, at least a second from now; a window when none streams. */
static double upload_retry_locked(struct connections *cs, const struct sockaddr_storage *addr,
                                  double now)
{
    double soonest = cs->cfg.upload_window_s;
    for (const struct conn *o = cs->head; o; o = o->next)
        if (o->upload && o->state == K_BODY && (!addr || same_address(&o->addr, addr))) {
            double left = o->window_start + cs->cfg.upload_window_s - now;
            if (left < soonest)
                soonest = left;
        }
    return soonest < 1 ? 1 : soonest;
}

bool connections_upload_begin(struct connections *cs, struct conn *k, double *retry_s)
{
    if (!k)
        return true;
    double now = clock_mono_s();
    pthread_mutex_lock(&cs->lock);
    unsigned held = 0;
    for (const struct conn *o = cs->head; o; o = o->next)
        held += o != k && o->upload && k->addr.ss_family && same_address(&o->addr, &k->addr);
    bool ok = !cs->cfg.uploads_per_ip || held < cs->cfg.uploads_per_ip;
    if (ok) {
        k->upload = true;
        k->window_start = now;
        k->window_bytes = 0;
    } else {
        *retry_s = upload_retry_locked(cs, &k->addr, now);
    }
    pthread_mutex_unlock(&cs->lock);
    return ok;
}

void connections_upload_bytes(struct connections *cs, struct conn *k, size_t bytes)
{
    if (!k)
        return;
    pthread_mutex_lock(&cs->lock);
    k->window_bytes += bytes;
    pthread_mutex_unlock(&cs->lock);
}

double connections_upload_retry_s(struct connections *cs)
{
    pthread_mutex_lock(&cs->lock);
    double s = upload_retry_locked(cs, NULL, clock_mono_s());
    pthread_mutex_unlock(&cs->lock);
    return s;
}

void connections_answering(struct connections *cs, struct conn *k)
{
    if (!k)
        return;
    pthread_mutex_lock(&cs->lock);
    if (k->state == K_BODY || k->state == K_HEADERS)
        k->state = K_ANSWERING;
    pthread_mutex_unlock(&cs->lock);
}

void connections_request_done(struct connections *cs, struct conn *k)
{
    if (!k)
        return;
    pthread_mutex_lock(&cs->lock);
    if (k->stopping_answer) {
        k->stopping_answer = false;
        cs->stopping_answers--;
        if (cs->waiting == 0 && cs->stopping_answers == 0)
            pthread_cond_broadcast(&cs->drained);
    }
    if (k->state != K_CUT && k->state != K_WAITING) {
        k->state = K_HEADERS;
        k->deadline = clock_mono_s() + cs->cfg.header_s;
        k->upload = false; /* its answer is out: the slot is free */
    }
    pthread_mutex_unlock(&cs->lock);
}

bool connections_is_reserve(const struct conn *k) { return k && k->reserve; }

void connections_set_status(struct conn *k, unsigned status)
{
    if (k)
        k->status = status;
}

unsigned connections_status(const struct conn *k) { return k ? k->status : 0; }

bool connections_suspend(struct connections *cs, struct conn *k, enum wait_kind kind,
                         const char *id, double wait_s)
{
    if (!k)
        return false;
    pthread_mutex_lock(&cs->lock);
    if (cs->stopping) {
        pthread_mutex_unlock(&cs->lock);
        return false;
    }
    k->state = K_WAITING;
    k->kind = kind;
    snprintf(k->id, sizeof(k->id), "%s", id);
    k->wait_until = clock_mono_s() + wait_s;
    k->wake = WAKE_NONE;
    /* Not EPOLLIN: a client may send its next request early; only a hang-up
     * ends the wait. */
    struct epoll_event ev = {.events = EPOLLRDHUP, .data.u64 = k->serial};
    if (epoll_ctl(cs->epfd, EPOLL_CTL_ADD, k->fd, &ev) != 0)
        LOG(LOG_DEBUG, "cannot watch a waiting connection for hang-ups: %s", strerror(errno));
    cs->waiting++;
    /* Under the lock, so that the watcher cannot resume it first. */
    MHD_suspend_connection(k->mhd);
    pthread_mutex_unlock(&cs->lock);
    /* The subject may have finished between the caller's look and now. */
    connections_poke(cs);
    return true;
}

enum wake connections_wake(const struct conn *k) { return k ? k->wake : WAKE_NONE; }

void connections_poke(struct connections *cs)
{
    uint64_t one = 1;
    ssize_t n = write(cs->evfd, &one, sizeof(one));
    (void)n; /* EAGAIN: the counter is already non-zero, the watcher will look */
}

void connections_stop(struct connections *cs, double grace_s)
{
    pthread_mutex_lock(&cs->lock);
    cs->stopping = true;
    pthread_mutex_unlock(&cs->lock);
    connections_poke(cs);
    struct timespec until;
    clock_gettime(CLOCK_MONOTONIC, &until);
    double at = (double)until.tv_sec + (double)until.tv_nsec / 1e9 + grace_s;
    until.tv_sec = (time_t)at;
    until.tv_nsec = (long)((at - (double)until.tv_sec) * 1e9);
    pthread_mutex_lock(&cs->lock);
    while (cs->waiting > 0 || cs->stopping_answers > 0)
        if (pthread_cond_timedwait(&cs->drained, &cs->lock, &until) == ETIMEDOUT)
            break;
    pthread_mutex_unlock(&cs->lock);
}

void connections_stats(struct connections *cs, struct connections_stats *out)
{
    pthread_mutex_lock(&cs->lock);
    out->open = cs->open;
    out->waiting = cs->waiting;
    out->header_timeouts = cs->header_timeouts;
    out->body_timeouts = cs->body_timeouts;
    out->waits_gone = cs->waits_gone;
    out->slow_uploads = cs->slow_uploads;
    out->uploads = 0;
    for (const struct conn *k = cs->head; k; k = k->next)
        out->uploads += k->upload;
    pthread_mutex_unlock(&cs->lock);
}
