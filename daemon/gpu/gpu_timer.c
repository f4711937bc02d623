#include "daemon/gpu/gpu_timer.h"

#include <stdlib.h>

#include "common/clock.h"

struct ring_slot {
    GLuint queries[GPU_TIMER_MAX_SECTIONS];
    bool issued[GPU_TIMER_MAX_SECTIONS];
    int64_t frame; /* -1 when nothing is waiting to be read */
};

struct gpu_timer {
    int sections;
    int64_t frames, next_frame;
    int current; /* running section, -1 when none */
    int last;    /* the section begun last, -1 before any */
    struct ring_slot ring[GPU_TIMER_RING];
    double *ms; /* frames * sections */
    unsigned char *implausible; /* per frame: sections whose answer was impossible */
    int64_t stalls;
    double created_s; /* clock_mono_s */
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
    for (int i = 0; i < GPU_TIMER_RING; i++) {
        glGenQueries(sections, t->ring[i].queries);
        t->ring[i].frame = -1;
    }
    return t;
}

void gpu_timer_destroy(struct gpu_timer *t)
{
    if (!t)
        return;
    for (int i = 0; i < GPU_TIMER_RING; i++)
        glDeleteQueries(t->sections, t->ring[i].queries);
    free(t->ms);
    free(t->implausible);
    free(t);
}

static void read_slot(struct gpu_timer *t, struct ring_slot *slot)
{
    if (slot->frame < 0)
        return;
    for (int s = 0; s < t->sections; s++) {
        if (!slot->issued[s])
            continue;
        GLint available = 0;
        glGetQueryObjectiv(slot->queries[s], GL_QUERY_RESULT_AVAILABLE, &available);
        if (!available)
            t->stalls++;
        GLuint64 ns = 0;
        glGetQueryObjectui64v(slot->queries[s], GL_QUERY_RESULT, &ns);
        double ms = (double)ns / 1e6;
        if (ms > (clock_mono_s() - t->created_s) * 1e3) {
            t->implausible[slot->frame]++;
            ms = 0.0;
        }
        t->ms[slot->frame * t->sections + s] = ms;
    }
    slot->frame = -1;
}

void gpu_timer_begin_frame(struct gpu_timer *t)
{
    struct ring_slot *slot = &t->ring[t->next_frame % GPU_TIMER_RING];
    read_slot(t, slot);
    for (int s = 0; s < t->sections; s++)
        slot->issued[s] = false;
    slot->frame = t->next_frame < t->frames ? t->next_frame : -1;
    t->current = -1;
    gpu_timer_section(t, 0);
}

void gpu_timer_section(struct gpu_timer *t, int s)
{
    if (s == t->current || s < 0 || s >= t->sections)
        return;
    t->last = s;
    struct ring_slot *slot = &t->ring[t->next_frame % GPU_TIMER_RING];
    if (t->current >= 0)
        glEndQuery(GL_TIME_ELAPSED);
    /* A section entered twice in one frame would need two queries; keep the
     * first and leave later work to the section that is running. */
    if (slot->issued[s]) {
        t->current = -1;
        return;
    }
    glBeginQuery(GL_TIME_ELAPSED, slot->queries[s]);
    slot->issued[s] = true;
    t->current = s;
}

void gpu_timer_end_frame(struct gpu_timer *t)
{
    if (t->current >= 0)
        glEndQuery(GL_TIME_ELAPSED);
    t->current = -1;
    t->next_frame++;
}

void gpu_timer_drain(struct gpu_timer *t)
{
    for (int i = 0; i < GPU_TIMER_RING; i++)
        read_slot(t, &t->ring[i]);
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
