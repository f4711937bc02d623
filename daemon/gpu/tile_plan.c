#include "daemon/gpu/tile_plan.h"

#include <string.h>

/* Samples: the first stage's units, the growth a stage, and the work (as a
 * fraction of a slice) above which a measure is read as reliable rather
 * than as timing noise. */
#define SAMPLE_FIRST_UNITS 16
#define SAMPLE_GROWTH 16
#define RELIABLE_FRACTION (1.0 / 16.0)
/* The rest: growth a tile over the largest so far (sixteenfold while the
 * last tile's work was too small to read). */
#define REST_GROWTH 4.0
#define REST_GROWTH_UNREAD 16.0

enum { PROBE, SAMPLES, REST, DONE };

void tile_plan_init(struct tile_plan *p, int w, int h, double slice_s, bool noisy)
{
    memset(p, 0, sizeof(*p));
    p->noisy = noisy;
    p->w = w > 0 ? w : 0;
    p->h = h > 0 ? h : 0;
    p->slice_s = slice_s;
    p->phase = p->w && p->h ? PROBE : DONE;
    p->stage_units = SAMPLE_FIRST_UNITS;
    /* Places spread over rows and, in a scrambled order, over columns; with
     * fewer rows than places, several a row, each free to grow up to the
     * next. */
    long long units = (long long)p->w * p->h;
    int n = units < TILE_PLAN_ANCHORS ? (int)units : TILE_PLAN_ANCHORS;
    p->nanchor = n;
    if (p->h >= n) {
        for (int j = 0; j < n; j++) {
            struct tile_plan_anchor *a = &p->anchor[j];
            a->row = (int)(((long long)j * 2 + 1) * p->h / (2 * n));
            a->col = (int)(((long long)((j * 5) % n) * 2 + 1) * p->w / (2 * n));
            a->end = a->col;
            a->limit = p->w;
        }
    } else {
        int per_row = (n + p->h - 1) / p->h;
        for (int j = 0; j < n; j++) {
            struct tile_plan_anchor *a = &p->anchor[j];
            int i = j % per_row;
            a->row = j / per_row;
            a->col = (int)(((long long)i * 2 + 1) * p->w / (2 * per_row));
            a->end = a->col;
            a->limit = i + 1 < per_row && j + 1 < n
                           ? (int)(((long long)(i + 1) * 2 + 1) * p->w / (2 * per_row))
                           : p->w;
        }
    }
    p->prev_units = SAMPLE_FIRST_UNITS;
}

double tile_plan_unit_max_s(const struct tile_plan *p)
{
    double mean = p->units > 0 ? p->work_s / p->units : 0.0;
    return p->unit_max_s > mean && !p->noisy ? p->unit_max_s : mean;
}

double tile_plan_fixed_s(const struct tile_plan *p)
{
    return p->measured ? p->cpu_min_s + p->gpu_min_s : 0.0;
}

double tile_plan_whole_s(const struct tile_plan *p)
{
    if (!p->measured)
        return 0.0;
    /* The least of each part once; above it, each tile's GPU time. */
    return p->cpu_min_s + p->gpu_sum_s - (p->measured - 1) * p->gpu_min_s;
}

/* The end of the drawn run that covers (x, y), or x when none does; and
 * the start of the next drawn run after x in row y, or w. */
static int hole_end(const struct tile_plan *p, int x, int y)
{
    for (int j = 0; j < p->nanchor; j++) {
        const struct tile_plan_anchor *a = &p->anchor[j];
        if (a->row == y && a->end > a->col && x >= a->col && x < a->end)
            return a->end;
    }
    return x;
}

static int next_hole(const struct tile_plan *p, int x, int y)
{
    int next = p->w;
    for (int j = 0; j < p->nanchor; j++) {
        const struct tile_plan_anchor *a = &p->anchor[j];
        if (a->row == y && a->end > a->col && a->col >= x && a->col < next)
            next = a->col;
    }
    return next;
}

static bool row_has_hole(const struct tile_plan *p, int y)
{
    for (int j = 0; j < p->nanchor; j++)
        if (p->anchor[j].row == y && p->anchor[j].end > p->anchor[j].col)
            return true;
    return false;
}

/* The rest of the units, in order: the next tile of about `want` units. */
static bool next_rest(struct tile_plan *p, double want, struct tile_rect *r)
{
    for (;;) {
        if (p->x >= p->w)
            p->x = 0, p->y++;
        if (p->y >= p->h)
            return false;
        int end = hole_end(p, p->x, p->y);
        if (end == p->x)
            break;
        p->x = end;
    }
    int run_end = next_hole(p, p->x, p->y);
    if (p->x == 0 && run_end == p->w && want >= p->w) {
        /* Whole rows: as many as want holds, none with a sample in it. */
        int rows = 1;
        double most = want / p->w;
        while (p->y + rows < p->h && rows + 1 <= most && !row_has_hole(p, p->y + rows))
            rows++;
        *r = (struct tile_rect){0, p->y, p->w, rows};
        p->y += rows;
        return true;
    }
    int len = run_end - p->x;
    if (want < len)
        len = want < 1 ? 1 : (int)want;
    *r = (struct tile_rect){p->x, p->y, len, 1};
    p->x += len;
    if (p->x >= p->w)
        p->x = 0, p->y++;
    return true;
}

/* The units a tile of the rest should hold: a slice of work at the dearest
 * cost a unit measured, less the fixed cost (at least half a slice each),
 * and at most fourfold the last tile. */
static double rest_units(const struct tile_plan *p)
{
    double grow = p->prev_units * (p->prev_read ? REST_GROWTH : REST_GROWTH_UNREAD);
    double unit = tile_plan_unit_max_s(p);
    if (unit <= 0)
        return grow;
    double per_tile = p->slice_s - tile_plan_fixed_s(p);
    if (per_tile < p->slice_s / 2)
        per_tile = p->slice_s / 2;
    double fit = per_tile / unit;
    return fit < grow ? (fit < 1 ? 1 : fit) : grow;
}

bool tile_plan_next(struct tile_plan *p, struct tile_rect *r)
{
    if (p->phase == PROBE) {
        struct tile_plan_anchor *a = &p->anchor[0];
        *r = (struct tile_rect){a->col, a->row, 1, 1};
        a->end = a->col + 1;
        p->last = *r;
        p->tiles++;
        return true;
    }
    while (p->phase == SAMPLES) {
        if (p->stage_next >= p->nanchor) {
            /* A stage done: a reliable measure, or nothing left to grow
             * into, ends the samples; else the next stage, sixteenfold. */
            bool room = false;
            for (int j = 0; j < p->nanchor; j++)
                room = room || p->anchor[j].end < p->anchor[j].limit;
            if (p->stage_max_work >= p->slice_s * RELIABLE_FRACTION || !room ||
                (double)p->stage_units * SAMPLE_GROWTH > (double)p->w * p->h / p->nanchor) {
                p->phase = REST;
                break;
            }
            p->stage_units *= SAMPLE_GROWTH;
            p->stage_next = 0;
            p->stage_max_work = 0;
        }
        struct tile_plan_anchor *a = &p->anchor[p->stage_next++];
        int len = a->limit - a->end;
        if (len > p->stage_units)
            len = p->stage_units;
        if (len <= 0)
            continue;
        *r = (struct tile_rect){a->end, a->row, len, 1};
        a->end += len;
        p->last = *r;
        p->tiles++;
        return true;
    }
    if (p->phase == REST && next_rest(p, rest_units(p), r)) {
        p->last = *r;
        p->tiles++;
        return true;
    }
    p->phase = DONE;
    return false;
}

void tile_plan_done(struct tile_plan *p, double cpu_s, double gpu_s)
{
    double units = (double)p->last.w * p->last.h;
    if (cpu_s < 0)
        cpu_s = 0;
    if (gpu_s < 0)
        gpu_s = 0;
    if (!p->measured || cpu_s < p->cpu_min_s)
        p->cpu_min_s = cpu_s;
    if (!p->measured || gpu_s < p->gpu_min_s)
        p->gpu_min_s = gpu_s;
    p->measured++;
    p->gpu_sum_s += gpu_s;
    if (p->phase == PROBE) {
        p->phase = SAMPLES;
        return;
    }
    double work = gpu_s - p->gpu_min_s;
    p->work_s += work;
    p->units += units;
    if (work >= p->slice_s * RELIABLE_FRACTION && units > 0 && work / units > p->unit_max_s)
        p->unit_max_s = work / units;
    if (p->phase == SAMPLES && work > p->stage_max_work)
        p->stage_max_work = work;
    /* Growth counts from the largest tile so far: a run cut short by a
     * sample or a row's end does not start it again. */
    if (units >= p->prev_units) {
        p->prev_units = units;
        p->prev_read = work >= p->slice_s * RELIABLE_FRACTION;
    }
}
