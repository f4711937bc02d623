#ifndef SHADEBENCH_TILE_PLAN_H
#define SHADEBENCH_TILE_PLAN_H

/* The tiles of a piece's measuring run (budget.h): which rectangles to
 * draw, one after another, each waited for alone, so that no tile holds the
 * GPU for much more than a slice although nothing is known of the piece
 * beforehand, and what the piece would cost drawn whole.
 *
 * The units are pixels of a w x h rectangle (or the items of a range, w x
 * 1), drawn exactly once, in rectangles a scissor can hold (a run within a
 * row, or whole rows).
 * 1. A probe of one unit: what every tile pays whatever its size (the
 *    geometry, its binning, the submission), the fixed cost.
 * 2. Samples spread over the piece (TILE_PLAN_ANCHORS places, over rows and
 *    columns), growing sixteenfold a stage while none carried a sixteenth of
 *    a slice above the fixed cost: a costly region (the objects under a
 *    cheap sky) is found before a large tile could land on it.
 * 3. The rest, in order, in tiles sized to a slice by the dearest cost a
 *    unit measured so far (or the mean, when that is higher), growing at
 *    most fourfold a tile (sixteenfold while a tile's work is too small to
 *    read against the timing noise).
 * A tile's cost comes in two parts: its submission on the CPU (a software
 * renderer such as llvmpipe shades and bins the vertices there, whatever
 * the tile's size) and its work on the GPU (a timer query, or the wall
 * clock less the submission where no query may run). The cost whole is the
 * least submission and the least GPU time of any tile once, plus what each
 * tile's GPU time came to above that least: a geometry-bound piece is not
 * charged its vertex work once a tile, and the waits of a loaded machine
 * (tens of milliseconds a round trip on 2 shared cores) are not summed.
 * GL-free and unit-tested (tests/unit/test_tile_plan.c); any thread. */

#include <stdbool.h>

#define TILE_PLAN_ANCHORS 4

struct tile_rect {
    int x, y, w, h;
};

struct tile_plan {
    int w, h;
    double slice_s;
    double cpu_min_s, gpu_min_s; /* the least submission and GPU time of any tile */
    double gpu_sum_s;  /* every tile's GPU time */
    double unit_max_s; /* the dearest reliably measured cost of a unit above the least */
    double work_s;     /* every tile's GPU time above the least so far, summed */
    double units;      /* units of the tiles after the probe */
    int measured;      /* tiles done */
    bool noisy;        /* wall-clock times: size by the mean */
    int phase;         /* 0 probe, 1 samples, 2 the rest, 3 done */
    int stage_units, stage_next;
    double stage_max_work;
    int nanchor;
    struct tile_plan_anchor {
        int row, col, end, limit; /* drawn: [col, end) of row; it may grow up to limit */
    } anchor[TILE_PLAN_ANCHORS];
    int x, y;          /* the rest: the next unit, row-major */
    double prev_units; /* the last tile's units */
    bool prev_read;    /* and whether its work was large enough to read */
    struct tile_rect last;
    int tiles;
};

/* noisy: the GPU times handed in are the wall clock's (no query could run),
 * each carrying a round trip's wait that a loaded machine stretches by tens
 * of milliseconds: tiles are then sized by the mean cost of a unit, not by
 * the dearest, which a wait on a small tile would inflate. */
void tile_plan_init(struct tile_plan *p, int w, int h, double slice_s, bool noisy);
/* The next tile to draw; false once every unit is drawn. */
bool tile_plan_next(struct tile_plan *p, struct tile_rect *r);
/* What the tile tile_plan_next last handed out took: its submission on the
 * CPU and its GPU time (0 and the whole round trip where neither can be
 * told apart, as for a dispatch a software renderer runs at the fence). */
void tile_plan_done(struct tile_plan *p, double cpu_s, double gpu_s);
/* What every tile pays whatever its size: the least submission and the
 * least GPU time of any tile. */
double tile_plan_fixed_s(const struct tile_plan *p);
/* The piece's cost drawn whole, by the measure (once every tile is done). */
double tile_plan_whole_s(const struct tile_plan *p);
/* The dearest a unit may cost above the fixed cost, for sizing the tiles
 * of later runs: the dearest reliable measure, or the mean if higher. */
double tile_plan_unit_max_s(const struct tile_plan *p);

#endif
