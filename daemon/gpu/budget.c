#include "daemon/gpu/budget.h"

#include <limits.h>
#include <math.h>
#include <string.h>

#include "common/clock.h"

/* A wait asks the stop predicate this often. */
#define WAIT_STEP_NS 5000000ull
#define BAND_ROWS 64
/* A piece's first run, which measures it, is drawn in this many tiles. */
#define MEASURE_TILES 16

static double slice_s = GPU_BUDGET_SLICE_S, free_s = GPU_BUDGET_FREE_S, max_fraction = 1.0;

void gpu_budget_configure(double slice, double free_below, double largest_fraction)
{
    slice_s = slice;
    free_s = free_below;
    max_fraction = largest_fraction;
}

void gpu_budget_limits(double *slice, double *free_below)
{
    *slice = slice_s;
    *free_below = free_s;
}

void gpu_budget_init(struct gpu_budget *b, bool (*stop)(void *ctx), void *ctx)
{
    memset(b, 0, sizeof(*b));
    b->stop = stop;
    b->ctx = ctx;
    b->loop_slot = -1;
}

static bool should_stop(struct gpu_budget *b)
{
    if (!b->stopped && b->stop && b->stop(b->ctx))
        b->stopped = true;
    return b->stopped;
}

bool gpu_budget_wait(struct gpu_budget *b, GLsync fence)
{
    if (!fence)
        return !gpu_budget_stopped(b);
    for (;;) {
        GLenum r = glClientWaitSync(fence, GL_SYNC_FLUSH_COMMANDS_BIT,
                                    b ? WAIT_STEP_NS : UINT64_MAX);
        if (r != GL_TIMEOUT_EXPIRED || !b || should_stop(b))
            break;
    }
    glDeleteSync(fence);
    if (b) {
        b->waits++;
        if (b->progress && !b->stopped)
            b->progress();
    }
    return !gpu_budget_stopped(b);
}

bool gpu_budget_sync(struct gpu_budget *b)
{
    return gpu_budget_wait(b, glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0));
}

/* The call's count from its site in this frame. */
static int nth_call(struct gpu_budget *b, const char *site)
{
    for (int i = 0; i < b->nseen; i++)
        if (b->seen[i].site == site)
            return b->seen[i].calls++;
    if (b->nseen < GPU_BUDGET_KEYS)
        b->seen[b->nseen++] = (struct gpu_budget_site){.site = site, .calls = 1};
    return 0;
}

static struct gpu_budget_piece *piece(struct gpu_budget *b, const char *site, int *slot)
{
    int nth = nth_call(b, site), free_slot = -1;
    for (int i = 0; i < GPU_BUDGET_KEYS; i++) {
        if (b->piece[i].site == site && b->piece[i].nth == nth) {
            *slot = i;
            return &b->piece[i];
        }
        if (!b->piece[i].site && free_slot < 0)
            free_slot = i;
    }
    /* More pieces than slots: the last one is shared, measured as one. */
    *slot = free_slot >= 0 ? free_slot : GPU_BUDGET_KEYS - 1;
    struct gpu_budget_piece *p = &b->piece[*slot];
    if (free_slot >= 0)
        *p = (struct gpu_budget_piece){.site = site, .nth = nth, .unit_s = -1.0,
                                       .whole_s = -1.0};
    return p;
}

/* What a run of the piece over `units` pixels or items should cost, from
 * its first run; < 0 before that. */
static double estimate_s(const struct gpu_budget_piece *p, double units)
{
    return p->unit_s < 0.0 ? -1.0 : p->unit_s * units;
}

static bool cheap(const struct gpu_budget_piece *p, double units)
{
    double s = estimate_s(p, units);
    return s >= 0.0 && s < free_s;
}

static bool loop_cheap(const struct gpu_budget_piece *p)
{
    return p->whole_s >= 0.0 && p->whole_s < free_s;
}

void gpu_tiles_begin_at(struct gpu_budget *b, const char *site, int w, int h,
                        struct gpu_tiles *t)
{
    *t = (struct gpu_tiles){.slot = -1, .w = w, .h = h, .first = true, .tw = w, .th = h};
    if (!b || b->stopped)
        return;
    struct gpu_budget_piece *p = piece(b, site, &t->slot);
    t->sliced = !cheap(p, (double)w * h);
    /* Measured alone: what earlier passes left in flight is not its cost. */
    if (t->sliced && p->unit_s < 0.0)
        gpu_budget_sync(b);
    t->prev_done = clock_mono_s();
}

void gpu_range_begin_at(struct gpu_budget *b, const char *site, int n, struct gpu_tiles *t)
{
    gpu_tiles_begin_at(b, site, n, 1, t);
    t->range = true;
}

/* Tile `slot` of the ring has finished by now: what it cost. The GPU had
 * it from when it was submitted or, if busy then, from when the tile before
 * it finished; a tile found finished when first asked counts the whole
 * span, an upper bound. */
static void tile_done(struct gpu_tiles *t, int slot, double now)
{
    double from = t->submit[slot] > t->prev_done ? t->submit[slot] : t->prev_done;
    t->total_s += now - from;
    t->prev_done = now;
}

/* Waits for the oldest tile in the ring and measures it. */
static bool retire(struct gpu_budget *b, struct gpu_budget_piece *p, struct gpu_tiles *t)
{
    int slot = t->oldest;
    bool go = gpu_budget_wait(b, t->fence[slot]);
    t->fence[slot] = NULL;
    (void)p;
    tile_done(t, slot, clock_mono_s());
    t->oldest = (t->oldest + 1) % GPU_TILES_IN_FLIGHT;
    t->in_flight--;
    return go;
}

bool gpu_tiles_next(struct gpu_budget *b, struct gpu_tiles *t)
{
    if (t->done)
        return false;
    if (!t->sliced || !b) {
        t->done = !t->first || gpu_budget_stopped(b);
        t->first = false;
        return !t->done;
    }
    struct gpu_budget_piece *p = &b->piece[t->slot];
    bool go = !should_stop(b);
    if (!t->first) {
        /* The tile just drawn joins the ring; the oldest is waited for once
         * the ring is full, so that the GPU always has tiles queued and at
         * most GPU_TILES_IN_FLIGHT are in flight. */
        int slot = (t->oldest + t->in_flight) % GPU_TILES_IN_FLIGHT;
        t->fence[slot] = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
        t->submit[slot] = t->cur_submit;
        t->px[slot] = t->drawn_px;
        t->in_flight++;
        glFlush();
        if (t->in_flight == GPU_TILES_IN_FLIGHT)
            go = retire(b, p, t);
    }
    if (!go || t->y >= t->h) {
        if (!t->range)
            glDisable(GL_SCISSOR_TEST);
        t->done = true;
        /* The piece's first run waits for its last tiles, to learn its whole
         * cost; later runs leave them queued. */
        bool measure = go && p->unit_s < 0.0;
        while (t->in_flight > 0) {
            if (measure) {
                go = retire(b, p, t) && go;
            } else {
                glDeleteSync(t->fence[t->oldest]);
                t->fence[t->oldest] = NULL;
                t->oldest = (t->oldest + 1) % GPU_TILES_IN_FLIGHT;
                t->in_flight--;
            }
        }
        if (measure && go && (double)t->w * t->h > 0)
            p->unit_s = t->total_s / ((double)t->w * t->h);
        b->pieces_sliced += t->tiles > 1;
        return false;
    }
    /* Equal tiles, as many as the piece's cost measured whole asks for
     * (MEASURE_TILES on its first run, while it is measured). */
    double whole = estimate_s(p, (double)t->w * t->h);
    double n = whole < 0.0 ? MEASURE_TILES : ceil(whole / slice_s);
    if (n < 1.0 / max_fraction)
        n = ceil(1.0 / max_fraction);
    double want = ceil((double)t->w * t->h / n);
    long long area = want < 1.0 ? 1 : (long long)want;
    int x = t->x, y = t->y, tw, th;
    if (t->x == 0 && area >= t->w) {
        long long rows = area / t->w;
        /* Whole bands of 64 rows where they fit: a software rasteriser such
         * as llvmpipe bins the screen in 64x64 blocks, and a tile that cuts
         * blocks leaves its threads idle at the tile's end. */
        if (rows >= BAND_ROWS && !t->range)
            rows -= rows % BAND_ROWS;
        th = rows < t->h - t->y ? (int)rows : t->h - t->y;
        tw = t->w;
        t->y += th;
    } else {
        tw = area < t->w - t->x ? (int)area : t->w - t->x;
        th = 1;
        t->x += tw;
        if (t->x >= t->w)
            t->x = 0, t->y++;
    }
    if (!t->range) {
        glEnable(GL_SCISSOR_TEST);
        glScissor(x, y, tw, th);
    }
    t->tx = x, t->ty = y, t->tw = tw, t->th = th;
    t->drawn_px = tw * th;
    t->tiles++;
    t->first = false;
    t->cur_submit = clock_mono_s();
    return true;
}

void gpu_loop_begin_at(struct gpu_budget *b, const char *site)
{
    if (!b)
        return;
    struct gpu_budget_piece *p = piece(b, site, &b->loop_slot);
    b->loop_calls = 0;
    if (loop_cheap(p)) {
        p->every = INT_MAX;
        return;
    }
    if (p->every <= 0 || p->every == INT_MAX) {
        p->every = 1;
        gpu_budget_sync(b);
    }
    b->loop_t0 = clock_mono_s();
}

bool gpu_loop_step(struct gpu_budget *b)
{
    if (!b || b->loop_slot < 0)
        return true;
    /* Asked every time: a loop of many cheap draws still takes a while on
     * the CPU, which no wait would notice. */
    if (should_stop(b))
        return false;
    struct gpu_budget_piece *p = &b->piece[b->loop_slot];
    if (p->every == INT_MAX || ++b->loop_calls % p->every != 0)
        return true;
    double t0 = clock_mono_s();
    bool go = gpu_budget_sync(b);
    double dt = clock_mono_s() - t0;
    /* Keep a chunk's GPU work near the aim: what the wait took is what the
     * chunk left unfinished, a lower bound of its cost. */
    if (dt < slice_s / 4 && p->every < INT_MAX / 4)
        p->every *= 2;
    else if (dt > slice_s * 2 && p->every > 1)
        p->every /= 2;
    return go;
}

void gpu_loop_end(struct gpu_budget *b)
{
    if (!b || b->loop_slot < 0)
        return;
    struct gpu_budget_piece *p = &b->piece[b->loop_slot];
    if (p->every != INT_MAX && gpu_budget_sync(b)) {
        p->whole_s = clock_mono_s() - b->loop_t0;
        b->pieces_sliced += b->loop_calls > p->every;
    }
    b->loop_slot = -1;
}
