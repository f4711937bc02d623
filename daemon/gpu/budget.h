#ifndef SHADEBENCH_GPU_BUDGET_H
#define SHADEBENCH_GPU_BUDGET_H

/* Bounded GPU submissions: no piece of a frame may keep the render thread
 * from a cancel, a timeout or a stop for long, whatever it costs. A pass's
 * screen-space work is drawn in tiles (a scissor rectangle each, the same
 * draws in each: the pixels are those of one draw) and a loop of many
 * draws takes checkpoints; wherever the GPU work between two waits could
 * exceed GPU_BUDGET_SLICE_S, the work is flushed and its fence waited for
 * in steps that ask the stop predicate. A piece of work that measured
 * below GPU_BUDGET_FREE_S as a whole runs as one submission with no wait at
 * all, so ordinary frames are drawn and timed as before; only its first
 * run (the first warm-up frame, normally) is measured in pieces.
 *
 * Every wait asks stop(ctx); once it answers true, the budget is stopped:
 * tiles and checkpoints end at once, and the caller abandons the frame
 * (gpu_budget_stopped), leaving at most one piece in flight.
 * Render thread only. */

#include <epoxy/gl.h>
#include <stdbool.h>
#include <stdint.h>

/* GPU work aimed at between two waits when a piece is sliced, seconds. */
#define GPU_BUDGET_SLICE_S 0.2
/* A piece measured below this as a whole runs unsliced. */
#define GPU_BUDGET_FREE_S 1.0
/* Tiles drawn ahead of the one waited for: the GPU always has work queued,
 * and at most this many tiles (GPU_BUDGET_SLICE_S each) are in flight. */
#define GPU_TILES_IN_FLIGHT 2
/* Pieces (tile loops, checkpoint loops) one run may tell apart. */
#define GPU_BUDGET_KEYS 128

/* A piece is a call site of gpu_tiles_begin, gpu_range_begin or
 * gpu_loop_begin and its nth call from there in a frame: a pass that some
 * frames skip (OSL's reshading with still lights) does not shift the pieces
 * after it onto another's measure. */
struct gpu_budget_piece {
    const char *site; /* __FILE__:__LINE__ of the call; NULL for an unused slot */
    int nth;          /* its calls from there before it in the frame */
    double unit_s;    /* tiles and ranges: the first run's seconds per pixel or item,
                       * so that the estimate follows the work a run is given; < 0
                       * before one */
    double whole_s;   /* loops: the last whole run, seconds; < 0 before one */
    int every;        /* checkpoints: calls between waits */
};

struct gpu_budget {
    bool (*stop)(void *ctx);
    void *ctx;
    /* Called when a wait has seen the GPU finish what it waited for (the
     * daemon's health check counts it as progress); may be NULL. */
    void (*progress)(void);
    bool stopped;
    int64_t waits;  /* fences waited for, in all */
    int64_t pieces_sliced; /* runs of a piece drawn in more than one tile or chunk */
    struct gpu_budget_piece piece[GPU_BUDGET_KEYS];
    /* Calls from each site so far in this frame. */
    struct gpu_budget_site {
        const char *site;
        int calls;
    } seen[GPU_BUDGET_KEYS];
    int nseen;
    /* checkpoint loop in progress */
    int loop_slot, loop_calls;
    double loop_t0;
};

void gpu_budget_init(struct gpu_budget *b, bool (*stop)(void *ctx), void *ctx);
/* Overrides GPU_BUDGET_SLICE_S and GPU_BUDGET_FREE_S for the process, and
 * bounds a tile to largest_fraction of its piece (the daemon's
 * SHADEBENCH_SLICE_MS, for tests: everything drawn in several tiles,
 * which must give the same pixels). Before any budget is used. */
void gpu_budget_configure(double slice_s, double free_s, double largest_fraction);
/* The slice and the bound below which a piece runs whole, as configured. */
void gpu_budget_limits(double *slice_s, double *free_s);
/* At the start of each frame (and of each set-up that draws): each site's
 * calls are counted from 0 again, so that the nth call from a site in every
 * frame is the same piece of work. */
static inline void gpu_budget_frame(struct gpu_budget *b)
{
    if (b)
        b->nseen = 0;
}
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
 * the tile (once with the scissor off when the piece is cheap). State the
 * body needs is set before the loop; a clear goes before it too, and the
 * body may not use the scissor itself. b may be NULL (no budget: one
 * unsliced run). */
struct gpu_tiles {
    int tx, ty, tw, th; /* the tile the body draws (the whole w x h when unsliced) */
    int slot, w, h;
    int x, y;       /* the next tile's origin */
    int drawn_px;   /* pixels of the tile in flight */
    bool sliced, first, done, range;
    /* Tiles drawn and not yet waited for, oldest first. */
    GLsync fence[GPU_TILES_IN_FLIGHT];
    double submit[GPU_TILES_IN_FLIGHT];
    int px[GPU_TILES_IN_FLIGHT];
    int oldest, in_flight;
    int tiles;     /* drawn so far */
    double cur_submit, prev_done, total_s;
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

/* Checkpoints in a loop of many draws or dispatches: gpu_loop_begin before
 * it, gpu_loop_step after each iteration (false: stopped, leave the loop),
 * gpu_loop_end after it. Between waits, as many iterations as keep the GPU
 * work near GPU_BUDGET_SLICE_S. */
void gpu_loop_begin_at(struct gpu_budget *b, const char *site);
#define gpu_loop_begin(b) gpu_loop_begin_at((b), GPU_BUDGET_SITE)
bool gpu_loop_step(struct gpu_budget *b);
void gpu_loop_end(struct gpu_budget *b);

#endif
