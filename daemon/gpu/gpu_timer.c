#include "daemon/gpu/gpu_timer.h"

#include <stdlib.h>
#include <string.h>

#include "common/clock.h"

/* A section may be entered more than once in a frame (a technique's first
 * pass, opened by the harness before the technique draws and again by the
 * technique itself after the look's shadow pass): each entry is timed on its
 * own, and the section's time is their sum. */
#define ENTRIES (2 * GPU_TIMER_MAX_SECTIONS)

/* One frame's queries. With timestamps, stamp[e] is written where entry e
 * begins and stamp[entries] where the frame ends: entry e took stamp[e + 1]
 * - stamp[e], and the entries add up to the frame's span exactly. Without,
 * each entry is a GL_TIME_ELAPSED query of its own. */
struct ring_slot {
    GLuint queries[ENTRIES + 1];
    int section[ENTRIES]; /* the section each entry timed */
    int entries;
    int64_t frame; /* -1 when nothing is waiting to be read */
};

struct gpu_timer {
    int sections;
    int64_t frames, next_frame;
    int current; /* running section, -1 when none */
    int last;    /* the section begun last, -1 before any */
    struct ring_slot ring[GPU_TIMER_RING];
    double *ms; /* frames * sections */
    bool timestamps; /* the driver answers GL_TIMESTAMP (bits > 0) */
    unsigned char *implausible; /* per frame: sections whose answer was impossible */
    int64_t stalls;
    double created_s; /* clock_mono_s */
    bool paused;
};

struct gpu_timer *gpu_timer_create(int sections, int64_t frames)
{
    if (sections < 1 || sections > GPU_TIMER_MAX_SECTIONS || frames < 1)
        return NULL;
    struct gpu_timer *t = calloc(1, sizeof(*t));
    if (!t)
        return NULL;
    t->ms = calloc((size_t)frames * (size_t)sections, sizeof(double));
    t->implausible = calloc((size_t)frames, 1);
    if (!t->ms || !t->implausible) {
        free(t->ms);
        free(t->implausible);
        free(t);
        return NULL;
    }
    t->sections = sections;
    t->frames = frames;
    t->created_s = clock_mono_s();
    t->current = -1;
    t->last = -1;
    GLint bits = 0;
    glGetQueryiv(GL_TIMESTAMP, GL_QUERY_COUNTER_BITS, &bits);
    t->timestamps = bits > 0;
    for (int i = 0; i < GPU_TIMER_RING; i++) {
        glGenQueries(ENTRIES + 1, t->ring[i].queries);
        t->ring[i].frame = -1;
    }
    return t;
}

void gpu_timer_destroy(struct gpu_timer *t)
{
    if (!t)
        return;
    for (int i = 0; i < GPU_TIMER_RING; i++)
        glDeleteQueries(ENTRIES + 1, t->ring[i].queries);
    free(t->ms);
    free(t->implausible);
    free(t);
}

static GLuint64 result_of(struct gpu_timer *t, GLuint query)
{
    GLint available = 0;
    glGetQueryObjectiv(query, GL_QUERY_RESULT_AVAILABLE, &available);
    if (!available)
        t->stalls++;
    GLuint64 ns = 0;
    glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
    return ns;
}

static void read_slot(struct gpu_timer *t, struct ring_slot *slot)
{
    if (slot->frame < 0)
        return;
    double *ms = &t->ms[slot->frame * t->sections];
    double since = (clock_mono_s() - t->created_s) * 1e3;
    for (int s = 0; s < t->sections; s++)
        ms[s] = 0.0;
    GLuint64 prev = slot->entries && t->timestamps ? result_of(t, slot->queries[0]) : 0;
    for (int e = 0; e < slot->entries; e++) {
        double v;
        if (t->timestamps) {
            GLuint64 next = result_of(t, slot->queries[e + 1]);
            v = next >= prev ? (double)(next - prev) / 1e6 : -1.0;
            prev = next > prev ? next : prev;
        } else {
            v = (double)result_of(t, slot->queries[e]) / 1e6;
        }
        if (v < 0 || v > since) {
            t->implausible[slot->frame]++;
            v = 0.0;
        }
        ms[slot->section[e]] += v;
    }
    slot->frame = -1;
}

void gpu_timer_pause(struct gpu_timer *t, bool paused)
{
    if (t)
        t->paused = paused;
}

void gpu_timer_begin_frame(struct gpu_timer *t)
{
    if (t->paused)
        return;
    struct ring_slot *slot = &t->ring[t->next_frame % GPU_TIMER_RING];
    read_slot(t, slot);
    slot->entries = 0;
    slot->frame = t->next_frame < t->frames ? t->next_frame : -1;
    t->current = -1;
}

void gpu_timer_section(struct gpu_timer *t, int s)
{
    if (t->paused && s >= 0 && s < t->sections)
        t->last = s; /* where the frame is, for messages */
    if (t->paused || s == t->current || s < 0 || s >= t->sections)
        return;
    t->last = s;
    struct ring_slot *slot = &t->ring[t->next_frame % GPU_TIMER_RING];
    if (t->current >= 0 && !t->timestamps)
        glEndQuery(GL_TIME_ELAPSED);
    t->current = -1;
    /* Past the entries a frame holds (never, with the passes declared):
     * later work goes to the section that ran last. */
    if (slot->entries >= ENTRIES)
        return;
    if (t->timestamps)
        glQueryCounter(slot->queries[slot->entries], GL_TIMESTAMP);
    else
        glBeginQuery(GL_TIME_ELAPSED, slot->queries[slot->entries]);
    slot->section[slot->entries++] = s;
    t->current = s;
}

void gpu_timer_end_frame(struct gpu_timer *t)
{
    if (t->paused)
        return;
    struct ring_slot *slot = &t->ring[t->next_frame % GPU_TIMER_RING];
    if (t->current >= 0 && !t->timestamps)
        glEndQuery(GL_TIME_ELAPSED);
    if (slot->entries && t->timestamps)
        glQueryCounter(slot->queries[slot->entries], GL_TIMESTAMP);
    t->current = -1;
    t->next_frame++;
}

void gpu_timer_drain(struct gpu_timer *t)
{
    for (int i = 0; i < GPU_TIMER_RING; i++)
        read_slot(t, &t->ring[i]);
}

void gpu_timer_restart(struct gpu_timer *t, int64_t next)
{
    gpu_timer_drain(t);
    memset(t->ms, 0, (size_t)t->frames * (size_t)t->sections * sizeof(double));
    memset(t->implausible, 0, (size_t)t->frames);
    t->next_frame = next > 0 ? next : 0;
    t->stalls = 0;
}

double gpu_timer_ms(const struct gpu_timer *t, int64_t f, int s)
{
    if (f < 0 || f >= t->frames)
        return 0.0;
    if (s >= 0)
        return s < t->sections ? t->ms[f * t->sections + s] : 0.0;
    double sum = 0.0;
    for (int i = 0; i < t->sections; i++)
        sum += t->ms[f * t->sections + i];
    return sum;
}

bool gpu_timer_timestamps(const struct gpu_timer *t) { return t->timestamps; }

int64_t gpu_timer_stalls(const struct gpu_timer *t) { return t->stalls; }

int gpu_timer_last_section(const struct gpu_timer *t) { return t->last; }

int64_t gpu_timer_implausible(const struct gpu_timer *t, int64_t from_frame)
{
    int64_t n = 0;
    for (int64_t f = from_frame < 0 ? 0 : from_frame; f < t->frames; f++)
        n += t->implausible[f];
    return n;
}

void gpu_timer_prime(void)
{
    /* The query must enclose work: llvmpipe starts its clock at the first
     * rendering it times. */
    GLuint q, tex, fbo;
    GLuint64 ns;
    glGenQueries(1, &q);
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA8, 4, 4);
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, 0);
    glBeginQuery(GL_TIME_ELAPSED, q);
    glClear(GL_COLOR_BUFFER_BIT);
    glEndQuery(GL_TIME_ELAPSED);
    glGetQueryObjectui64v(q, GL_QUERY_RESULT, &ns);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glBindTexture(GL_TEXTURE_2D, 0);
    glDeleteFramebuffers(1, &fbo);
    glDeleteTextures(1, &tex);
    glDeleteQueries(1, &q);
}
