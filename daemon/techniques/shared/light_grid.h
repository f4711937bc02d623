#ifndef SHADEBENCH_LIGHT_GRID_H
#define SHADEBENCH_LIGHT_GRID_H

/* The light grid of the tiled and clustered techniques: screen tiles (with
 * per-tile depth bounds from the depth buffer) or froxels (tiles cut into
 * linear or exponential depth slices), each cell holding the indices of the
 * lights whose spheres touch it, in ascending order, so that a loop over a
 * cell's list sums exactly as forward's loop over every light does.
 *
 * GPU binning (shaders/culling/): a bit per light and cell set by one
 * invocation per light over the cells its screen rectangle and depth range
 * cover, then one invocation per cell compacting its bits into a list; a
 * summary bit per word of bits lets compaction visit (and zero for the next
 * frame) only the words that hold lights, so no pass touches every cell's
 * every word. CPU
 * binning (tiles only, seed 003): the lists built from each light's screen
 * rectangle on the CPU every frame and uploaded, inside the timed region.
 *
 * Lists are packed into one index buffer of bounded capacity; clusters keep
 * at most max_per_cell lights. A cell over the bound, or that finds the
 * buffer full, is flagged: under the fallback policy it shades with every light (correct,
 * slower); under fail, light_grid_verify fails the job. Either way every
 * frame's overflowed cells and dropped lights are counted on the GPU into a
 * per-frame record read back once after the run (never in the timed
 * region) and reported by light_grid_describe. Render thread only. */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/techniques/shared/culling_info.h"
#include "daemon/techniques/technique.h"

enum light_grid_kind { LIGHT_GRID_TILES, LIGHT_GRID_CLUSTERS };

/* Frames whose grids exist at once: more than the harness keeps in flight. */
#define LIGHT_GRID_RING 3

struct light_grid_config {
    int kind;          /* enum light_grid_kind */
    int tile_size;     /* tiles: edge in pixels */
    int grid[3];       /* clusters: cells in x, y and z */
    int slices;        /* clusters: enum cluster_slices */
    int max_per_cell;  /* clusters: the bound on a cell's list; tiles: 0 */
    int overflow;      /* enum cluster_overflow (tiles always fall back) */
    int binning;       /* enum light_binning (cpu: tiles only) */
    const char *technique; /* its name, for messages naming its fields */
};

/* std140 layout of shaders/culling/light_grid.glsl's LightGridBlock. */
struct light_grid_block {
    int32_t dims[4];  /* cells in x, y, z; cells in all */
    float tile[4];    /* tile width, height (pixels); reciprocals */
    float slices[4];  /* depth where slicing starts, ends; slices per unit; 1 = exponential */
    int32_t lists[4]; /* max per cell (0: by offset), capacity, bit words per cell, fallback */
    int32_t counts[4]; /* lights, statistics record of this frame, summary words per cell */
};

/* One frame's record, written by light_compact.comp (or the CPU binning). */
struct light_grid_stats {
    uint32_t overflow_cells, lights_dropped, fullest, handed_out, kept, nonempty, spare[2];
};

struct light_grid {
    struct light_grid_config cfg;
    struct light_grid_block block;
    int cells, words, lights, width, height, frames;
    bool camera_moves; /* slices follow the camera's depth range every frame */
    long long capacity; /* index entries */
    GLuint tile_depth_buf, bits_buf, summary_buf, stats_buf;
    /* Each frame writes the next of a ring of blocks and lists, so that
     * neither an upload nor a compute pass waits for a frame still in
     * flight that reads the previous ones (on llvmpipe such a write
     * hazard stalls the CPU until that frame is rasterised). */
    GLuint ubo[LIGHT_GRID_RING], cells_buf[LIGHT_GRID_RING], index_buf[LIGHT_GRID_RING];
    int ring;
    int scatter_groups[2]; /* the scatter pass's dispatch: an invocation per light */
    GLuint depth_prog, scatter_prog, compact_prog;
    double buffer_bytes;
    double *bin_ms; /* CPU time of each timed frame's binning */
    struct light_grid_stats *stats; /* frames + 1 records: 0 is warm-up */
    bool stats_read;
    /* CPU binning scratch, allocated at init. */
    int *rects;
    uint32_t *counts, *cells_host, *index_host;
};

/* Builds buffers and programs and checks the grid against the device
 * (storage-buffer size, compute work-group counts), failing with a message
 * that names the option to change. On failure call light_grid_finish. */
bool light_grid_init(struct light_grid *g, const struct technique_env *env,
                     const struct light_grid_config *cfg, char *err, size_t errlen);
/* Accepts a zeroed or half-built g. */
void light_grid_finish(struct light_grid *g);

/* Builds frame's lists, inside the caller's binning pass. Tiles read the
 * depth texture env->output_depth (filled by the pass before). The light
 * positions of frame must be uploaded already. */
void light_grid_build(struct light_grid *g, const struct technique_env *env, int64_t frame);

/* Binds the block and the lists for a shading program. */
void light_grid_bind(const struct light_grid *g);

/* After the run: false (err names the option) when a light list overflowed
 * under the fail policy. */
bool light_grid_verify(struct light_grid *g, char *err, size_t errlen);

/* Grid, lists, overflow counts and binning time for the result. New
 * reference. */
json_t *light_grid_describe(struct light_grid *g);

#endif
