#ifndef SHADEBENCH_POW2_ATLAS_H
#define SHADEBENCH_POW2_ATLAS_H

/* Tiles of power-of-two sizes placed in an atlas, each aligned to its own
 * size, edge to edge: OSL's shading atlas and the look's shadow atlas both
 * place their tiles with it. Pure; any thread. */

struct atlas_tile {
    int x, y, size;
};

/* Places tiles of power-of-two sizes, largest first (equal sizes in index
 * order), each at the next Z-order position of its size, in an atlas of
 * w x h texels (h a power of two at least the largest size, w a multiple
 * of h) whose area holds them all; order is scratch for count ints. Never
 * allocates, so the shadow atlas packs with it every frame. */
void atlas_place(const int *sizes, int count, int w, int h, int *order,
                 struct atlas_tile *tiles);

#endif
