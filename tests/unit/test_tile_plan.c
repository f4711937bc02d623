/* The measuring run's tiles (daemon/gpu/tile_plan.h) on simulated pieces:
 * every unit drawn once, no tile far over a slice where a costly region
 * lies under a cheap one (the 16-tile measure of before drew a sixteenth of
 * a frame of 15 s, and one tile over the objects held the render thread for
 * 88 s after a timeout), the cost whole with the fixed cost counted once,
 * and few tiles where the piece is cheap. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/gpu/tile_plan.h"
#include "tests/unit/check.h"

/* A piece: what every tile pays, and each unit's cost. */
struct sim {
    int w, h;
    double fixed; /* the submission's cost (a software renderer's vertex work) */
    double (*cost)(const struct sim *s, int x, int y);
    double param;
};

static double uniform(const struct sim *s, int x, int y)
{
    (void)x, (void)y;
    return s->param;
}

/* A cheap sky over the top rows, costly objects under it (forward with
 * 16,384 lights at 128x128: about 4.5 ms a pixel on a loaded 2-core box). */
static double sky_then_objects(const struct sim *s, int x, int y)
{
    (void)x;
    return y < s->h / 6 ? 1e-7 : s->param;
}

/* One costly object in a corner of a cheap frame. */
static double corner_object(const struct sim *s, int x, int y)
{
    return x > s->w * 7 / 8 && y > s->h * 7 / 8 ? s->param : 2e-8;
}

struct outcome {
    int tiles, overdrawn, missed;
    double worst_tile_s, whole_s, true_whole_s;
};

static struct outcome run(const struct sim *s, double slice)
{
    struct outcome o = {0};
    unsigned char *drawn = calloc((size_t)s->w * s->h, 1);
    struct tile_plan p;
    tile_plan_init(&p, s->w, s->h, slice, false);
    struct tile_rect r;
    o.true_whole_s = s->fixed;
    for (int y = 0; y < s->h; y++)
        for (int x = 0; x < s->w; x++)
            o.true_whole_s += s->cost(s, x, y);
    unsigned seed = 7;
    while (tile_plan_next(&p, &r) && o.tiles < 1000000) {
        double t = s->fixed, work = 0;
        CHECK(r.x >= 0 && r.y >= 0 && r.w >= 1 && r.h >= 1 && r.x + r.w <= s->w &&
              r.y + r.h <= s->h);
        for (int y = r.y; y < r.y + r.h; y++)
            for (int x = r.x; x < r.x + r.w; x++) {
                if (drawn[(size_t)y * s->w + x]++)
                    o.overdrawn++;
                work += s->cost(s, x, y);
            }
        t += work;
        if (t > o.worst_tile_s)
            o.worst_tile_s = t;
        /* A loaded machine preempts the submission now and then. */
        seed = seed * 1103515245u + 12345u;
        double preempted = (seed >> 16) % 4 == 0 ? 0.05 : 0.0;
        tile_plan_done(&p, s->fixed + preempted, work + 1e-5);
        o.tiles++;
    }
    for (size_t i = 0; i < (size_t)s->w * s->h; i++)
        o.missed += drawn[i] == 0;
    o.whole_s = tile_plan_whole_s(&p);
    free(drawn);
    return o;
}

static void report(const char *what, const struct outcome *o)
{
    printf("%-40s %6d tiles, worst %.3f s, whole %.3f s (true %.3f s)\n", what, o->tiles,
           o->worst_tile_s, o->whole_s, o->true_whole_s);
}

int main(void)
{
    const double slice = 0.2;

    /* Each piece: every unit drawn once; no tile past worst slices; at
     * most tiles tiles (0: any); the cost whole within error of the truth
     * (0: not asked). */
    static const struct {
        const char *what;
        struct sim sim;
        double worst, error;
        int tiles;
    } cases[] = {
        /* The runaway test's frame (forward, 16,384 lights at 128x128). */
        {"sky over objects, 128x128, 4.5 ms/px", {128, 128, 0.005, sky_then_objects, 4.5e-3},
         2.5, 0.01, 0},
        /* 65,536 lights at 256x256: 241 s a frame unloaded. */
        {"65,536 lights, 256x256", {256, 256, 0.01, uniform, 3.7e-3}, 2.5, 0.05, 0},
        /* A geometry-bound pass: the fixed cost counted once, not once a tile. */
        {"geometry-bound, 640x480, 40 ms a tile", {640, 480, 0.04, uniform, 1e-9}, 1.0, 0.2, 25},
        {"cheap, 1080x720", {1080, 720, 0.002, uniform, 3e-8}, 1.0, 0.2, 25},
        /* Forward with 256 lights at 1080x720 on llvmpipe. */
        {"moderate, 1080x720, 2 s whole", {1080, 720, 0.003, uniform, 2.6e-6}, 2.5, 0.02, 0},
        /* A costly object in a corner of a cheap frame: a sample may miss it. */
        {"costly corner, 512x512", {512, 512, 0.002, corner_object, 1e-4}, 3.0, 0, 0},
        /* A range of work items (a dispatch's groups). */
        {"range of 100,000 items", {100000, 1, 0.0005, uniform, 5e-5}, 2.5, 0.01, 0},
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
        struct outcome o = run(&cases[i].sim, slice);
        report(cases[i].what, &o);
        CHECK(o.overdrawn == 0 && o.missed == 0);
        CHECK(o.worst_tile_s < cases[i].worst * slice);
        CHECK(!cases[i].tiles || o.tiles < cases[i].tiles);
        CHECK(!cases[i].error || fabs(o.whole_s - o.true_whole_s) < cases[i].error * o.true_whole_s);
    }
    /* Wall-clock times (no query: a dispatch, set-up work): a loaded
     * machine adds tens of milliseconds to a tile now and then. Sized by
     * the mean, a cheap piece stays in few tiles (by the dearest tile, the
     * waits read as costly pixels cut it into hundreds). */
    for (int noisy = 0; noisy < 2; noisy++) {
        struct tile_plan p;
        struct tile_rect r;
        tile_plan_init(&p, 256, 256, slice, noisy);
        unsigned seed = 11;
        int tiles = 0;
        while (tile_plan_next(&p, &r) && tiles < 100000) {
            seed = seed * 1103515245u + 12345u;
            double wait = (seed >> 16) % 3 == 0 ? 0.06 : 0.002;
            tile_plan_done(&p, 0.0, wait + (double)r.w * r.h * 3e-8);
            tiles++;
        }
        printf("cheap 256x256 with waits, sized by the %s: %d tiles\n", noisy ? "mean" : "dearest",
               tiles);
        CHECK(noisy ? tiles < 40 : tiles > 100);
    }
    int sizes[][2] = {{1, 1}, {3, 1}, {1, 5}, {7, 3}, {64, 48}, {5, 200}};
    for (size_t i = 0; i < sizeof(sizes) / sizeof(sizes[0]); i++) {
        struct sim tiny = {sizes[i][0], sizes[i][1], 0.001, uniform, 1e-6};
        struct outcome o = run(&tiny, slice);
        CHECK(o.overdrawn == 0 && o.missed == 0 && o.tiles >= 1);
    }
    return check_finish("test_tile_plan");
}
