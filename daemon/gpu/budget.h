#ifndef SHADEBENCH_GPU_BUDGET_H
#define SHADEBENCH_GPU_BUDGET_H

/* Bounded GPU submissions: no piece of untimed work may keep the render
 * thread from a cancel, a timeout or a stop for long, whatever it costs,
 * and timed work is drawn exactly as it would be without the guard.
 *
 * A piece is a pass's screen-space work drawn in tiles (a scissor rectangle
 * each, the same draws in each: the pixels are those of one draw), a
 * dispatch's work items in ranges, or a loop of many draws that takes
 * checkpoints. What the budget does with a piece depends on its mode:
 *
 * - GPU_BUDGET_ADAPTIVE, for untimed work (a run's measuring frame, the
 *   look's set-up, the reference, temporal frames): a piece's first run is
 *   measured in the tiles tile_plan.h lays out (a one-unit probe, whose cost
 *   is what every tile pays whatever its size: the geometry, its binning,
 *   the submission; samples spread over the piece; then tiles sized to a
 *   slice by the dearest cost a unit measured), each waited for alone,
 *   which gives its cost whole as the probe's cost plus what each tile cost
 *   above it, so that a geometry-bound pass is not charged its vertex work
 *   once a tile; later runs are drawn in tiles of about GPU_BUDGET_SLICE_S
 *   (by the dearest unit's cost) wherever that measure says a run takes a
 *   slice or more.
 * - GPU_BUDGET_WHOLE, for the timed frames (and the frame that decides
 *   whether they may be drawn whole): one submission per piece, no tile and
 *   no wait, exactly as without the guard; a stop is seen at the frame's
 *   fence (daemon/harness/measure.c decides, from the measuring frame and
 *   one whole frame, that a whole frame fits the render thread's bound).
 * - GPU_BUDGET_SLICED, for the timed frames of a job that accepted sliced
 *   timing: every piece in the tiles its measure asks for, the same count
 *   in every frame (fixed at its first sliced run).
 *
 * Every wait asks stop(ctx); once it answers true, the budget is stopped:
 * tiles and checkpoints end at once, and the caller abandons the frame
 * (gpu_budget_stopped), leaving at most one piece in flight.
 * Render thread only. */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stdint.h>

#include "daemon/gpu/gpu_timer.h"
#include "daemon/gpu/tile_plan.h"

/* GPU work aimed at between two waits when a piece is sliced, seconds. */
#define GPU_BUDGET_SLICE_S 0.2
/* Tiles drawn ahead of the one waited for when a measured piece is drawn
 * in tiles: the GPU always has work queued, and at most this many tiles
 * (about a slice each) are in flight. A measuring run waits for each. */
#define GPU_TILES_IN_FLIGHT 2
/* Pieces (tile loops, checkpoint loops) one run may tell apart. */
#define GPU_BUDGET_KEYS 128

enum gpu_budget_mode { GPU_BUDGET_ADAPTIVE, GPU_BUDGET_WHOLE, GPU_BUDGET_SLICED };

/* A piece is a call site of gpu_tiles_begin, gpu_range_begin or
 * gpu_loop_begin and its nth call from there in a frame: a pass that some
 * frames skip (OSL's reshading with still lights) does not shift the pieces
 * after it onto another's measure. */
struct gpu_budget_piece {
    const char *site; /* __FILE__:__LINE__ of the call; NULL for an unused slot */
    int nth;          /* its calls from there before it in the frame */
    int pass;         /* the timer section it was measured in (-1: unknown) */
    double unit_s;    /* tiles and ranges: seconds the dearest pixel or item costs above
                       * the fixed cost, from its measured run, so that tiles follow
                       * the work a run is given; < 0 before one */
    double fixed_s;   /* tiles and ranges: what a tile costs whatever its size */
    double whole_s;   /* its measured run's cost drawn whole (loops: the run's) */
    int every;        /* loops: calls between waits */
    int tiles;        /* GPU_BUDGET_SLICED: tiles a run, fixed once (0: not yet) */
};

/* What one frame's pieces did (reset by gpu_budget_frame). */
struct gpu_budget_frame {
    int sliced_runs;   /* runs of a piece drawn in more than one tile or chunk */
    double measured_s; /* seconds the pieces measured in it took, in their tiles */
    double whole_s;    /* what those pieces would take drawn whole, by their measure */
    double fixed_s;    /* the part of it no pixel pays for (a tile's fixed cost, a loop) */
    int largest_pass;  /* the pass of the dearest piece measured (-1: none) */
    double largest_s;  /* and its cost whole */
};

struct gpu_budget {
    bool (*stop)(void *ctx);
    void *ctx;
    /* Called when a wait has seen the GPU finish what it waited for (the
     * daemon's health check counts it as progress); may be NULL. */
    void (*progress)(void);
    /* The frame's timer, when the caller has one: a measured piece notes
     * the pass it ran in, for messages. May be NULL. */
    const struct gpu_timer *timer;
    enum gpu_budget_mode mode;
    /* A measured tile's GPU time is read from a GL_TIME_ELAPSED query (set
     * only where no timer section is open: the harness's measuring frames,
     * with the run's timer paused); else from the wall clock, which on a
     * loaded machine adds every round trip's wait. */
    bool use_queries;
    /* A measuring run gives up (stops the budget, over set) once what its
     * pieces have cost so far, counted whole, passes this many seconds (0:
     * never): the frame cannot fit the bound, and drawing the rest of it
     * would only hold the render thread. */
    double give_up_s;
    bool stopped, over;
    int64_t waits;         /* fences waited for, in all */
    int64_t pieces_sliced; /* runs of a piece drawn in more than one tile or chunk */
    struct gpu_budget_frame frame;
    struct gpu_budget_piece piece[GPU_BUDGET_KEYS];
    /* Calls from each site so far in this frame. */
    struct gpu_budget_site {
        const char *site;
        int calls;
    } seen[GPU_BUDGET_KEYS];
    int nseen;
    int frames_begun; /* gpu_budget_frame calls so far */
    /* checkpoint loop in progress */
    int loop_slot, loop_calls;
    double loop_t0;
    bool loop_measuring;
};

void gpu_budget_init(struct gpu_budget *b, bool (*stop)(void *ctx), void *ctx);
/* Overrides GPU_BUDGET_SLICE_S for the process, and bounds a tile to
 * largest_fraction of its piece wherever a piece is drawn in tiles (the
 * daemon's SHADEBENCH_SLICE_MS, for tests: every piece drawn in several
 * tiles, which must give the same pixels). Before any budget is used. */
void gpu_budget_configure(double slice_s, double largest_fraction);
/* The slice, as configured. */
double gpu_budget_slice(void);
/* Tests only (SHADEBENCH_DEBUG_STALL_FIRST_FRAME_MS): every wait in the
 * first frame a budget draws sleeps stall_s first, as a loaded or
 * throttled machine would make that frame's pieces look slower. */
void gpu_budget_debug_stall(double stall_s);
/* Forgets every piece's measure, so that the next run of each is measured
 * again (a second measuring frame). */
void gpu_budget_forget(struct gpu_budget *b);
/* At the start of each frame (and of each set-up that draws): each site's
 * calls are counted from 0 again, so that the nth call from a site in every
 * frame is the same piece of work, and the frame's figures start anew. */
void gpu_budget_frame(struct gpu_budget *b);
#define GPU_BUDGET_STR_(x) #x
#define GPU_BUDGET_STR(x) GPU_BUDGET_STR_(x)
#define GPU_BUDGET_SITE __FILE__ ":" GPU_BUDGET_STR(__LINE__)
static inline bool gpu_budget_stopped(const struct gpu_budget *b) { return b && b->stopped; }

/* Waits for fence (deleting it), asking stop every few milliseconds. False
 * when stopped first (the fence is deleted all the same). */
bool gpu_budget_wait(struct gpu_budget *b, GLsync fence);
/* Flushes and waits for all work submitted so far. */
bool gpu_budget_sync(struct gpu_budget *b);

/* Tiles: for (gpu_tiles_begin(b, w, h, &t); gpu_tiles_next(b, &t);)
 * draw(); draws the loop's body once per tile with GL_SCISSOR_TEST set to
 * the tile (once with the scissor off when the piece is drawn whole). State
 * the body needs is set before the loop; a clear goes before it too, and
 * the body may not use the scissor itself. b may be NULL (no budget: one
 * whole run). */
struct gpu_tiles {
    int tx, ty, tw, th; /* the tile the body draws (the whole w x h when unsliced) */
    int slot, w, h;
    int x, y;       /* the next tile's origin */
    int drawn_px;   /* units of the tile in flight */
    bool sliced, first, done, range, measuring;
    int ntiles;     /* sliced and not measuring: tiles this run */
    /* Tiles drawn and not yet waited for, oldest first. */
    GLsync fence[GPU_TILES_IN_FLIGHT];
    int oldest, in_flight;
    int tiles;      /* drawn so far */
    double cur_submit;
    /* measuring: the run's start, its tiles, and the query timing the tile
     * in flight (0: none) */
    double begun;
    struct tile_plan plan;
    GLuint query;
};
void gpu_tiles_begin_at(struct gpu_budget *b, const char *site, int w, int h,
                        struct gpu_tiles *t);
#define gpu_tiles_begin(b, w, h, t) gpu_tiles_begin_at((b), GPU_BUDGET_SITE, (w), (h), (t))
bool gpu_tiles_next(struct gpu_budget *b, struct gpu_tiles *t);
/* The same over a range of n work items (w = n, h = 1) that is not drawn,
 * such as a compute dispatch's groups: the body reads [t.tx, t.tx + t.tw),
 * and the scissor is left alone. */
void gpu_range_begin_at(struct gpu_budget *b, const char *site, int n, struct gpu_tiles *t);
#define gpu_range_begin(b, n, t) gpu_range_begin_at((b), GPU_BUDGET_SITE, (n), (t))

/* An indirect dispatch whose group count the GPU wrote (into the buffer
 * bound at GL_DISPATCH_INDIRECT_BUFFER, at offset): drawn whole as
 * glDispatchComputeIndirect wherever the budget draws whole; where it
 * slices, the count is read back (after a wait: untimed work only) and the
 * groups dispatched in ranges. The program in use must number its groups
 * base_loc + gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x and
 * leave those at or past end_loc (uint uniforms; the whole dispatch gets 0
 * and UINT_MAX). groups_x_max: the device's GL_MAX_COMPUTE_WORK_GROUP_COUNT
 * in x. */
void gpu_dispatch_indirect_at(struct gpu_budget *b, const char *site, GLintptr offset,
                              GLint base_loc, GLint end_loc, int groups_x_max);
#define gpu_dispatch_indirect(b, offset, base_loc, end_loc, groups_x_max)                        \
    gpu_dispatch_indirect_at((b), GPU_BUDGET_SITE, (offset), (base_loc), (end_loc), (groups_x_max))

/* Checkpoints in a loop of many draws or dispatches: gpu_loop_begin before
 * it, gpu_loop_step after each iteration (false: stopped, leave the loop),
 * gpu_loop_end after it. Between waits, as many iterations as keep the GPU
 * work near GPU_BUDGET_SLICE_S; none where the budget draws whole. */
void gpu_loop_begin_at(struct gpu_budget *b, const char *site);
#define gpu_loop_begin(b) gpu_loop_begin_at((b), GPU_BUDGET_SITE)
bool gpu_loop_step(struct gpu_budget *b);
void gpu_loop_end(struct gpu_budget *b);

#endif
