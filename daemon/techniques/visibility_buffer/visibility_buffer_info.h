#ifndef SHADEBENCH_VISIBILITY_BUFFER_INFO_H
#define SHADEBENCH_VISIBILITY_BUFFER_INFO_H

/* The visibility buffer's GL-free half: its options ("visibility_buffer":
 * {"lights", "ids", and the cluster grid's when lights is "clustered"}),
 * its passes, and the packing of a pixel's ids. Any thread. */

#include <stdbool.h>
#include <stdint.h>

#include "daemon/techniques/shared/culling_info.h"
#include "daemon/techniques/technique_info.h"

/* Which lights the shading pass loops over. */
enum vis_lights {
    VIS_LIGHTS_ALL,       /* every light, as forward */
    VIS_LIGHTS_CLUSTERED, /* the pixel's froxel's list (the clustered techniques' grid) */
};
/* How a pixel's instance and triangle are stored. */
enum vis_ids {
    VIS_IDS_AUTO, /* 32 bits when the instances and the largest mesh's triangles fit, else 64 */
    VIS_IDS_WIDE, /* 64 bits (RG32UI) always */
};

struct visibility_buffer_options {
    int lights; /* enum vis_lights */
    int ids;    /* enum vis_ids */
    struct cluster_options cluster;
};

extern const struct technique_info visibility_buffer_info;

/* Bits a pixel's 32-bit id gives its triangle when instances (+1 for
 * "none") and triangles (of the largest mesh) share 32 bits: the fewest
 * that hold max_triangles, or -1 when the two do not fit in 32 (the ids
 * then take 64 bits). */
int vis_triangle_bits(long long instances, long long max_triangles);

/* One pixel's 32-bit id: (instance + 1) above triangle_bits bits of
 * triangle; 0 is no surface. vis_unpack is its inverse (false for 0). */
uint32_t vis_pack(int instance, uint32_t triangle, int triangle_bits);
bool vis_unpack(uint32_t id, int triangle_bits, int *instance, uint32_t *triangle);

#endif
