#define _POSIX_C_SOURCE 200809L
#include "daemon/status/render_state.h"

#include <stdatomic.h>
#include <stdint.h>
#include <string.h>

#include "common/clock.h"

/* The job's id as atomic words, so that a reader racing a writer reads
 * torn words (and retries), never undefined behaviour. */
#define ID_WORDS ((RECORD_ID_LEN + 7) / 8)

static atomic_uint seq; /* odd while the render thread rewrites the fields below */
static atomic_ullong id_words[ID_WORDS];
static atomic_bool busy;
static atomic_llong begun_ns;
/* Outside the sequence lock: single stores, read on their own. */
static _Atomic(const char *) phase;
static atomic_llong progress_ns;

static long long to_ns(double s) { return (long long)(s * 1e9); }

void render_progress_at(double mono_s)
{
    atomic_store_explicit(&progress_ns, to_ns(mono_s), memory_order_relaxed);
}

void render_progress(void) { render_progress_at(clock_mono_s()); }

/* Render thread only: the sequence lock has one writer. */
static void write_job(const char *job_id, bool is_busy, long long now)
{
    unsigned s = atomic_load_explicit(&seq, memory_order_relaxed);
    atomic_store_explicit(&seq, s + 1, memory_order_relaxed);
    atomic_thread_fence(memory_order_release);
    unsigned long long words[ID_WORDS] = {0};
    if (job_id) {
        size_t n = strnlen(job_id, RECORD_ID_LEN - 1);
        memcpy(words, job_id, n);
    }
    for (int i = 0; i < ID_WORDS; i++)
        atomic_store_explicit(&id_words[i], words[i], memory_order_relaxed);
    atomic_store_explicit(&busy, is_busy, memory_order_relaxed);
    atomic_store_explicit(&begun_ns, now, memory_order_relaxed);
    atomic_store_explicit(&seq, s + 2, memory_order_release);
}

void render_state_begin(const char *job_id, const char *ph)
{
    long long now = to_ns(clock_mono_s());
    atomic_store_explicit(&phase, ph, memory_order_relaxed);
    atomic_store_explicit(&progress_ns, now, memory_order_relaxed);
    write_job(job_id, true, now);
}

void render_state_phase(const char *ph)
{
    atomic_store_explicit(&phase, ph, memory_order_relaxed);
    render_progress();
}

void render_state_end(void)
{
    long long now = to_ns(clock_mono_s());
    atomic_store_explicit(&progress_ns, now, memory_order_relaxed);
    write_job(NULL, false, now);
    atomic_store_explicit(&phase, NULL, memory_order_relaxed);
}

void render_state_read(struct render_state *out)
{
    unsigned long long words[ID_WORDS];
    bool is_busy;
    long long begun;
    for (;;) {
        unsigned s1 = atomic_load_explicit(&seq, memory_order_acquire);
        for (int i = 0; i < ID_WORDS; i++)
            words[i] = atomic_load_explicit(&id_words[i], memory_order_relaxed);
        is_busy = atomic_load_explicit(&busy, memory_order_relaxed);
        begun = atomic_load_explicit(&begun_ns, memory_order_relaxed);
        atomic_thread_fence(memory_order_acquire);
        if (!(s1 & 1) && atomic_load_explicit(&seq, memory_order_relaxed) == s1)
            break;
    }
    memset(out, 0, sizeof(*out));
    memcpy(out->job, words, RECORD_ID_LEN - 1);
    out->job[RECORD_ID_LEN - 1] = '\0';
    double now = clock_mono_s();
    long long progress = atomic_load_explicit(&progress_ns, memory_order_relaxed);
    out->busy = is_busy;
    out->phase = is_busy ? atomic_load_explicit(&phase, memory_order_relaxed) : NULL;
    if (is_busy && !out->phase)
        out->phase = "starting";
    out->busy_s = is_busy && begun > 0 ? now - (double)begun / 1e9 : 0;
    /* Progress made just before a job began reads as that job's start. */
    double since = now - (double)(progress > begun ? progress : begun) / 1e9;
    out->since_progress_s = since > 0 ? since : 0;
}

bool render_state_stalled(const struct render_state *s, double bound_s)
{
    return s->alive && s->busy && bound_s > 0 && s->since_progress_s > bound_s;
}
