/* Binding points shared by C and GLSL: this file is included by the C code
 * and prepended to every shader, so the two can never disagree. Only
 * #define lines belong here. Any thread (constants only). */
#ifndef SB_BINDINGS_H
#define SB_BINDINGS_H

/* Uniform blocks. */
#define SB_UBO_FRAME 0

/* Shader storage blocks. */
#define SB_SSBO_INSTANCES 0
#define SB_SSBO_LIGHTS 1
#define SB_SSBO_LIGHT_POSITIONS 2
#define SB_SSBO_OSL_TILES 3
#define SB_SSBO_OSL_WORK 4
#define SB_SSBO_LIGHT_GRID 5    /* per tile or cluster: offset, count */
#define SB_SSBO_LIGHT_INDICES 6 /* the lists the grid points into */
#define SB_SSBO_CULL_STATS 7    /* overflow and evaluation counters */

/* Texture units. */
#define SB_TEX_HDR 0
#define SB_TEX_DEPTH 1
#define SB_TEX_GBUFFER0 2 /* 2..5: g-buffer planes */
#define SB_TEX_OSL_ATLAS 0
#define SB_TEX_OSL_MESH 1 /* 1 + 2m: position of mesh m, 2 + 2m: normal */

/* Image units. */
#define SB_IMG_OSL_ATLAS 0

#endif
