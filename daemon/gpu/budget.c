#define _POSIX_C_SOURCE 200809L
#include "daemon/gpu/budget.h"

#include <limits.h>
#include <math.h>
#include <string.h>
#include <time.h>

#include "common/clock.h"

/* A wait asks the stop predicate this often. */
#define WAIT_STEP_NS 5000000ull
#define BAND_ROWS 64

static double slice_s = GPU_BUDGET_SLICE_S, max_fraction = 1.0, debug_stall_s;

void gpu_budget_configure(double slice, double largest_fraction)
{
    slice_s = slice;
    max_fraction = largest_fraction > 0 && largest_fraction <= 1 ? largest_fraction : 1.0;
}

double gpu_budget_slice(void) { return slice_s; }

void gpu_budget_debug_stall(double stall) { debug_stall_s = stall > 0 ? stall : 0; }

void gpu_budget_init(struct gpu_budget *b, bool (*stop)(void *ctx), void *ctx)
{
    memset(b, 0, sizeof(*b));
    b->stop = stop;
    b->ctx = ctx;
    b->loop_slot = -1;
    b->frame.largest_pass = -1;
}

void gpu_budget_forget(struct gpu_budget *b)
{
    memset(b->piece, 0, sizeof(b->piece));
}

void gpu_budget_frame(struct gpu_budget *b)
{
    if (!b)
        return;
    b->nseen = 0;
    b->frames_begun++;
    b->frame = (struct gpu_budget_frame){.largest_pass = -1};
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
    if (b && debug_stall_s > 0 && b->frames_begun == 1) {
        struct timespec ts = {(time_t)debug_stall_s,
                              (long)((debug_stall_s - (double)(time_t)debug_stall_s) * 1e9)};
        nanosleep(&ts, NULL);
    }
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
        *p = (struct gpu_budget_piece){.site = site, .nth = nth, .pass = -1, .unit_s = -1.0,
                                       .whole_s = -1.0};
    return p;
}

/* A measured piece's run over `units` pixels or items cut into tiles that
 * each take about a slice: a tile pays the fixed cost whatever its size, so
 * each carries work of at least half a slice. 1: whole. */
static int tiles_for(const struct gpu_budget_piece *p, double units)
{
    double work = p->unit_s * units, per_tile = slice_s - p->fixed_s;
    if (per_tile < slice_s / 2)
        per_tile = slice_s / 2;
    double n = ceil(work / per_tile);
    return n < 1 ? 1 : n > 1e6 ? 1000000 : (int)n;
}

/* The tiles of a run that is not measured: none (whole) or some, by mode. */
static int planned_tiles(struct gpu_budget_piece *p, enum gpu_budget_mode mode, double units)
{
    int n = 1;
    if (mode == GPU_BUDGET_SLICED) {
        if (p->tiles <= 0)
            p->tiles = tiles_for(p, units);
        n = p->tiles;
    } else if (p->fixed_s + p->unit_s * units >= slice_s) {
        n = tiles_for(p, units);
    }
    /* Tests: every piece that is cut at all in at least 1 / max_fraction tiles. */
    int least = (int)ceil(1.0 / max_fraction);
    if (max_fraction < 1.0 && n < least)
        n = least;
    return n;
}

static void begin(struct gpu_budget *b, const char *site, int w, int h, bool range,
                  struct gpu_tiles *t)
{
    *t = (struct gpu_tiles){.slot = -1, .w = w, .h = h, .first = true, .tw = w, .th = h,
                            .range = range};
    if (!b || b->stopped || b->mode == GPU_BUDGET_WHOLE || (double)w * h <= 0)
        return;
    struct gpu_budget_piece *p = piece(b, site, &t->slot);
    if (p->unit_s < 0.0) {
        /* Measured alone: what earlier passes left in flight is not its cost. */
        t->sliced = t->measuring = true;
        bool query = b->use_queries && !range;
        tile_plan_init(&t->plan, w, h, slice_s, !query);
        if (query)
            glGenQueries(1, &t->query);
        gpu_budget_sync(b);
        t->begun = clock_mono_s();
        if (b->timer)
            p->pass = gpu_timer_last_section(b->timer);
        return;
    }
    t->ntiles = planned_tiles(p, b->mode, (double)w * h);
    t->sliced = t->ntiles > 1;
}

void gpu_tiles_begin_at(struct gpu_budget *b, const char *site, int w, int h,
                        struct gpu_tiles *t)
{
    begin(b, site, w, h, false, t);
}

void gpu_range_begin_at(struct gpu_budget *b, const char *site, int n, struct gpu_tiles *t)
{
    begin(b, site, n, 1, true, t);
}

/* A measuring run's last tile: waited for alone, and what it cost (its
 * submission, then its GPU time). A dispatch (a range) counts its whole
 * round trip as work: a software renderer runs it at the fence. */
static bool measure_tile(struct gpu_budget *b, struct gpu_budget_piece *p, struct gpu_tiles *t)
{
    double cpu = clock_mono_s() - t->cur_submit;
    if (t->query)
        glEndQuery(GL_TIME_ELAPSED);
    GLsync fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
    glFlush();
    if (!gpu_budget_wait(b, fence))
        return false;
    double wall = clock_mono_s() - t->cur_submit;
    double gpu = wall - cpu;
    if (t->query) {
        GLuint64 ns = 0;
        glGetQueryObjectui64v(t->query, GL_QUERY_RESULT, &ns);
        /* Longer than the tile's whole round trip is impossible: a driver's
         * fault (llvmpipe answers the first query after compute work with
         * the time since boot); the wall clock stands in. */
        double q = (double)ns / 1e9;
        /* Tests: the stalled first frame is a slow GPU's too (the wall
         * clock has the stall in it already). */
        if (q <= wall)
            gpu = q + (b->frames_begun == 1 ? debug_stall_s : 0.0);
    }
    if (t->range)
        tile_plan_done(&t->plan, 0.0, wall);
    else
        tile_plan_done(&t->plan, cpu, gpu);
    /* What the frame's measured pieces have cost whole so far: once past
     * the bound, a whole frame cannot fit it. */
    double so_far = tile_plan_whole_s(&t->plan);
    if (b->give_up_s > 0 && b->frame.whole_s + so_far > b->give_up_s) {
        b->stopped = b->over = true;
        /* Cut short: what it has cost so far names it. */
        if (so_far > b->frame.largest_s) {
            b->frame.largest_s = so_far;
            b->frame.largest_pass = p->pass;
        }
        return false;
    }
    return true;
}

/* The end of a sliced run: the scissor off, the ring's tiles left queued
 * (a measuring run has none), the measure kept. */
static void tiles_end(struct gpu_budget *b, struct gpu_budget_piece *p, struct gpu_tiles *t,
                      bool go)
{
    if (!t->range)
        glDisable(GL_SCISSOR_TEST);
    t->done = true;
    if (t->query) {
        glDeleteQueries(1, &t->query);
        t->query = 0;
    }
    while (t->in_flight > 0) {
        glDeleteSync(t->fence[t->oldest]);
        t->fence[t->oldest] = NULL;
        t->oldest = (t->oldest + 1) % GPU_TILES_IN_FLIGHT;
        t->in_flight--;
    }
    if (t->measuring && go) {
        p->fixed_s = tile_plan_fixed_s(&t->plan);
        p->unit_s = tile_plan_unit_max_s(&t->plan);
        p->whole_s = tile_plan_whole_s(&t->plan);
        b->frame.measured_s += clock_mono_s() - t->begun;
        b->frame.whole_s += p->whole_s;
        b->frame.fixed_s += t->range ? 0.0 : p->fixed_s;
        if (p->whole_s > b->frame.largest_s) {
            b->frame.largest_s = p->whole_s;
            b->frame.largest_pass = p->pass;
        }
    }
    if (t->tiles > 1) {
        b->pieces_sliced++;
        b->frame.sliced_runs++;
    }
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
        if (t->measuring) {
            go = measure_tile(b, p, t) && go;
        } else {
            /* The tile just drawn joins the ring; the oldest is waited for
             * once the ring is full, so that the GPU always has tiles queued
             * and at most GPU_TILES_IN_FLIGHT are in flight. */
            int slot = (t->oldest + t->in_flight) % GPU_TILES_IN_FLIGHT;
            t->fence[slot] = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
            t->in_flight++;
            glFlush();
            if (t->in_flight == GPU_TILES_IN_FLIGHT) {
                go = gpu_budget_wait(b, t->fence[t->oldest]) && go;
                t->fence[t->oldest] = NULL;
                t->oldest = (t->oldest + 1) % GPU_TILES_IN_FLIGHT;
                t->in_flight--;
            }
        }
    }
    if (t->measuring) {
        struct tile_rect r;
        if (!go || !tile_plan_next(&t->plan, &r)) {
            tiles_end(b, p, t, go);
            return false;
        }
        if (!t->range) {
            glEnable(GL_SCISSOR_TEST);
            glScissor(r.x, r.y, r.w, r.h);
        }
        t->tx = r.x, t->ty = r.y, t->tw = r.w, t->th = r.h;
        t->drawn_px = r.w * r.h;
        t->tiles++;
        t->first = false;
        t->cur_submit = clock_mono_s();
        if (t->query)
            glBeginQuery(GL_TIME_ELAPSED, t->query);
        return true;
    }
    if (!go || t->y >= t->h) {
        tiles_end(b, p, t, go);
        return false;
    }
    double want = ceil((double)t->w * t->h / t->ntiles);
    long long area = want < 1.0 ? 1 : want > 1e15 ? (long long)1e15 : (long long)want;
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

void gpu_dispatch_indirect_at(struct gpu_budget *b, const char *site, GLintptr offset,
                              GLint base_loc, GLint end_loc, int groups_x_max)
{
    bool whole = !b || b->stopped || b->mode == GPU_BUDGET_WHOLE;
    if (whole) {
        glUniform1ui(base_loc, 0u);
        glUniform1ui(end_loc, UINT_MAX);
        glDispatchComputeIndirect(offset);
        return;
    }
    /* Untimed or sliced: the count the GPU wrote, read back once the work
     * before has finished (that wait asks the stop predicate too). */
    GLuint groups[3] = {0, 0, 0};
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
    if (!gpu_budget_sync(b))
        return;
    glGetBufferSubData(GL_DISPATCH_INDIRECT_BUFFER, offset, sizeof(groups), groups);
    double n = (double)groups[0] * groups[1] * groups[2];
    if (n <= 0)
        return;
    if (n > INT_MAX)
        n = INT_MAX;
    if (groups_x_max < 1)
        groups_x_max = 65535;
    struct gpu_tiles t;
    for (gpu_range_begin_at(b, site, (int)n, &t); gpu_tiles_next(b, &t);) {
        GLuint count = (GLuint)t.tw;
        GLuint gx = count < (GLuint)groups_x_max ? count : (GLuint)groups_x_max;
        GLuint gy = (count + gx - 1) / gx;
        glUniform1ui(base_loc, (GLuint)t.tx);
        glUniform1ui(end_loc, (GLuint)(t.tx + t.tw));
        glDispatchCompute(gx, gy, 1);
    }
}

void gpu_loop_begin_at(struct gpu_budget *b, const char *site)
{
    if (!b)
        return;
    struct gpu_budget_piece *p = piece(b, site, &b->loop_slot);
    b->loop_calls = 0;
    b->loop_measuring = false;
    if (b->mode == GPU_BUDGET_WHOLE ||
        (b->mode == GPU_BUDGET_ADAPTIVE && p->whole_s >= 0.0 && p->whole_s < slice_s)) {
        p->every = p->every > 0 ? p->every : 1;
        b->loop_calls = INT_MIN; /* no checkpoint this run */
        return;
    }
    if (p->whole_s < 0.0) {
        /* Its first run: checkpoints from every call on, doubling while the
         * chunks stay short, and its cost whole. */
        b->loop_measuring = true;
        p->every = 1;
        if (b->timer)
            p->pass = gpu_timer_last_section(b->timer);
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
    if (b->loop_calls < 0)
        return true;
    struct gpu_budget_piece *p = &b->piece[b->loop_slot];
    if (++b->loop_calls % p->every != 0)
        return true;
    double t0 = clock_mono_s();
    bool go = gpu_budget_sync(b);
    double dt = clock_mono_s() - t0;
    /* Keep a chunk's GPU work near the aim: what the wait took is what the
     * chunk left unfinished, a lower bound of its cost. A sliced timed run
     * keeps the chunks its measure gave. */
    if (b->mode != GPU_BUDGET_SLICED || b->loop_measuring) {
        if (dt < slice_s / 4 && p->every < INT_MAX / 4)
            p->every *= 2;
        else if (dt > slice_s * 2 && p->every > 1)
            p->every /= 2;
    }
    double so_far = clock_mono_s() - b->loop_t0;
    if (go && b->loop_measuring && b->give_up_s > 0 && b->frame.whole_s + so_far > b->give_up_s) {
        b->stopped = b->over = true;
        go = false;
        if (so_far > b->frame.largest_s) {
            b->frame.largest_s = so_far;
            b->frame.largest_pass = p->pass;
        }
    }
    return go;
}

void gpu_loop_end(struct gpu_budget *b)
{
    if (!b || b->loop_slot < 0)
        return;
    struct gpu_budget_piece *p = &b->piece[b->loop_slot];
    if (b->loop_calls >= 0 && gpu_budget_sync(b)) {
        double took = clock_mono_s() - b->loop_t0;
        if (b->loop_measuring) {
            p->whole_s = took;
            b->frame.measured_s += took;
            b->frame.whole_s += took;
            b->frame.fixed_s += took; /* a loop of draws: per light or face, not per pixel */
            if (took > b->frame.largest_s) {
                b->frame.largest_s = took;
                b->frame.largest_pass = p->pass;
            }
        }
        if (b->loop_calls > p->every) {
            b->pieces_sliced++;
            b->frame.sliced_runs++;
        }
    }
    b->loop_slot = -1;
}
