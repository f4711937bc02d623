/* Binding points shared by C and GLSL: this file is included by the C code
 * and prepended to every shader, so the two can never disagree. Only
 * #define lines belong here. Any thread (constants only). */
#ifndef SB_BINDINGS_H
#define SB_BINDINGS_H

/* Uniform blocks. */
#define SB_UBO_FRAME 0
#define SB_UBO_LIGHT_GRID 1 /* light grid dimensions, slices, list bounds */
#define SB_UBO_IBL 2 /* the probes lighting this frame (shaders/common/ibl.glsl) */

/* Shader storage blocks. */
#define SB_SSBO_INSTANCES 0
#define SB_SSBO_LIGHTS 1
#define SB_SSBO_LIGHT_POSITIONS 2
#define SB_SSBO_OSL_TILES 3
#define SB_SSBO_OSL_WORK 4
#define SB_SSBO_LIGHT_GRID 5    /* per tile or cluster: offset, count */
#define SB_SSBO_LIGHT_INDICES 6 /* the lists the grid points into */
#define SB_SSBO_CULL_STATS 7    /* overflow and evaluation counters */
#define SB_SSBO_LIGHT_BITS 8    /* per cell, one bit per light while binning */
#define SB_SSBO_TILE_DEPTH 9    /* per tile: nearest and farthest view depth */
#define SB_SSBO_NONFINITE 10    /* the harness's NaN and infinity pixel counters */
#define SB_SSBO_LIGHT_SUMMARY 11 /* per cell, one bit per non-zero word of light bits */
#define SB_SSBO_SHADOW_LIGHTS 12 /* per light: where its shadow map's faces lie */
#define SB_SSBO_EDGE_STATS 13   /* MSAA g-buffer: edge pixels this frame and over the run */
/* OSL's visibility "seen" (osl_select.comp): per atlas block its instance
 * and the shading it holds; per instance the shading its schedule asks for;
 * the blocks selected this frame; the pass's counters and indirect dispatch. */
#define SB_SSBO_OSL_BLOCK_TILE 14
#define SB_SSBO_OSL_SHADED 15
#define SB_SSBO_OSL_VERSIONS 16
#define SB_SSBO_OSL_LIST 17
#define SB_SSBO_OSL_STATS 18
/* Asset scenes (SCENE_TEXTURED): one SurfaceMaterial per asset material,
 * and glTF's default material after them (shaders/common/surface.glsl). */
#define SB_SSBO_MATERIALS 19
#define SB_SSBO_SHADOW_SUNS 20 /* per directional light's map: its projection */
#define SB_SSBO_PREV_INSTANCES 21 /* per instance: its position and scale the frame before (motion vectors) */
/* The visibility buffer's copy of every mesh's vertices and indices, and per mesh
 * where its own begin and its material (daemon/techniques/visibility_buffer/). */
#define SB_SSBO_VIS_VERTICES 22
#define SB_SSBO_VIS_INDICES 23
#define SB_SSBO_VIS_MESHES 24

/* Texture units. */
#define SB_TEX_HDR 0
#define SB_TEX_DEPTH 1
#define SB_TEX_GBUFFER0 2 /* 2..5: g-buffer planes */
#define SB_TEX_GBUFFER1 3
#define SB_TEX_GBUFFER2 4
#define SB_TEX_OSL_ATLAS 0
#define SB_TEX_OSL_GEO_POSITION 1 /* OSL's geometry atlas: object-space positions */
#define SB_TEX_OSL_GEO_NORMAL 2   /* and normals */
#define SB_TEX_OSL_GEO_ALBEDO 3   /* asset scenes: base colour and roughness baked */
#define SB_TEX_OSL_GEO_SURFACE 4  /* and emissive and occlusion */
#define SB_TEX_OSL_ATLAS_SPECULAR 1 /* OSL's raster pass, asset scenes under Phong: specular light */
#define SB_TEX_POST_SRC 0    /* post effects: the colour the effect reads */
#define SB_TEX_POST_DEPTH 1  /* the technique's depth texture */
#define SB_TEX_POST_NORMAL 2 /* the technique's g-buffer normals, when it has them */
#define SB_TEX_POST_AUX 3    /* an effect's own intermediate (bloom level, occlusion) */
#define SB_TEX_POST_MOTION 4 /* the harness's motion vectors (an effect that needs them: TAA) */

/* Uniform locations, explicit so that timed code never looks a name up.
 * Arrays take one location per element. */
#define SB_LOC_EXPOSURE 0     /* resolve: float */
#define SB_LOC_GAMMA 1        /* resolve: float, 0 for the sRGB curve, else a plain gamma */
#define SB_LOC_POST_PARAMS 0  /* post effects: vec4 of the effect's options */
#define SB_LOC_POST_WEIGHTS 1 /* bloom: float[33] Gaussian weights */
#define SB_LOC_SSAO_NOISE 1   /* ssao: float[16] rotation angles */
#define SB_LOC_SSAO_KERNEL 17 /* ssao: vec4[64] hemisphere samples */

/* Harness-owned units, bound before every frame's passes for the lighting
 * library (look.ibl, look.shadows): techniques leave 10 and up alone. */
#define SB_TEX_IBL_SOURCE 10      /* setup only: the cube map being filtered */
#define SB_TEX_ENV_MAP 11         /* the sky pass: an uploaded equirectangular environment */
#define SB_TEX_IBL_IRRADIANCE 12  /* cube map array: environment, then each probe */
#define SB_TEX_IBL_PREFILTERED 13 /* cube map array, roughness picks the level */
#define SB_TEX_IBL_BRDF 14        /* the split sum's (A, B) table */
#define SB_TEX_SHADOW_ATLAS 15    /* depth atlas of every light's six faces */
#define SB_TEX_SHADOW_CUBES 16    /* or a depth cube map array, a layer a light */
#define SB_TEX_SHADOW_SUNS 17     /* depth array: a layer a directional light */
/* Asset scenes: the drawn mesh's material textures, bound by gpu_scene_draw
 * before each asset mesh's draw (one unit a glTF slot, in enum
 * asset_texture_slot order; a slot without a texture is never sampled). */
#define SB_TEX_MATERIAL_BASE_COLOR 20
#define SB_TEX_MATERIAL_METALLIC_ROUGHNESS 21
#define SB_TEX_MATERIAL_NORMAL 22
#define SB_TEX_MATERIAL_OCCLUSION 23
#define SB_TEX_MATERIAL_EMISSIVE 24
#define SB_TEX_GBUFFER3 5 /* asset scenes' g-buffer: emissive, occlusion */

/* Uniform locations of the harness's own programs, explicit so that timed
 * code never looks a name up. */
#define SB_LOC_SHADOW_VIEW_PROJ 0 /* mat4, locations 0..3 */
#define SB_LOC_SHADOW_INSTANCE 4  /* int */
/* Every program that draws scene meshes, asset scenes only: the drawn
 * mesh's index into the material buffer, set by gpu_scene_draw (and the
 * shadow pass) per asset mesh. */
#define SB_LOC_MATERIAL 5         /* int */
/* The same, look.debug's programs only: which of the file's vertex
 * attributes the drawn mesh has (bit 0 TEXCOORD_0, 1 TEXCOORD_1, 2 COLOR_0),
 * set by gpu_scene_draw where the program reads it. */
#define SB_LOC_MESH_ATTRIBUTES 6  /* int */
/* The visibility buffer's material passes: the window depth of the material
 * key a full-screen draw stands at (vis_key.vert). */
#define SB_LOC_VIS_KEY 7          /* float */
#define SB_LOC_IBL_FACE 0         /* filters: int, the cube face written */
#define SB_LOC_IBL_PARAMS 1       /* filters: vec4 (roughness or lod, 1 / size, samples, source size) */

/* Image units. */
#define SB_IMG_OSL_ATLAS 0
#define SB_IMG_HEAT 1 /* light evaluations per pixel (r32ui) */
#define SB_IMG_OSL_MARKS 2 /* per atlas block, the last frame the raster pass sampled it (r32i) */
#define SB_IMG_OSL_ATLAS_SPECULAR 3 /* OSL, asset scenes under Phong: the specular plane */

#endif
