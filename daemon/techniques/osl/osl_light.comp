// OSL lighting pass: one 8x8 block of one object's tile per work group. The
// work list holds one entry per object to shade: (instance, light row,
// first block, blocks per tile row); a group finds its entry by binary search.
// With OSL_BLOCK_LIST (osl.visibility "seen") the groups come from an
// indirect dispatch over the blocks osl_select.comp listed: (atlas block,
// light row) each.
#include "lighting.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// x, y, size, and where the object's geometry lies in the geometry atlas
// (x + 65536 y).
layout(std430, binding = SB_SSBO_OSL_TILES) readonly buffer TileBuffer { ivec4 tiles[]; };
layout(std430, binding = SB_SSBO_OSL_WORK) readonly buffer WorkBuffer { uvec4 work[]; };
#if defined(SCENE_TEXTURED)
layout(rgba16f, binding = SB_IMG_OSL_ATLAS) writeonly uniform image2D u_atlas; // asset scenes: HDR
#else
layout(rgba8, binding = SB_IMG_OSL_ATLAS) writeonly uniform image2D u_atlas;
#endif

// The geometry atlas: every mesh's object-space position (w = 1 where a
// texel is covered) and normal, once per tile size in use.
uniform sampler2D u_position;
uniform sampler2D u_normal;
#if defined(SCENE_TEXTURED)
// Asset scenes: the material baked by osl_texgen.frag. The normal's w is
// metallic.
uniform sampler2D u_albedo;  // linear base colour, roughness (+ 2 for a double-sided material)
uniform sampler2D u_surface; // emissive, occlusion

// Every light on a baked texel, as surface_shade_all_lights (surface.glsl)
// shades a fragment: ambient scaled by occlusion, emissive after lighting,
// Phong's terms from roughness as material_surface_grad derives them.
vec3 shade_baked(vec3 P, vec3 N, float metallic, vec4 albedo, vec4 surface, int row)
{
    bool two_sided = albedo.a >= 2.0;
    float roughness = albedo.a - (two_sided ? 2.0 : 0.0);
    Material m = Material(albedo.rgb, 0.04 + 0.96 * metallic,
                          max(1.0, 2.0 / max(roughness * roughness, 1e-3) - 2.0), metallic,
                          roughness);
    vec3 V = normalize(u_frame.eye.xyz - P);
    // The side the eye sees, as the other techniques' gl_FrontFacing picks
    // it (here from the shading normal: a normal map near the silhouette
    // can tip a texel to the other side).
    if (two_sided && dot(N, V) < 0.0)
        N = -N;
    vec3 color = surface.a * light_ambient(m, P, N, V);
    for (int i = 0; i < u_frame.counts.y; i++)
        color += light_contribution(i, light_position(i, row), P, N, V, m);
    return color + surface.rgb;
}
#endif
uniform int u_work_count;
uniform int u_groups_x;
// The dispatch may cover a range of the blocks (or, with OSL_BLOCK_LIST, of
// the listed slots) only (bounded submissions, daemon/gpu/budget.h): groups
// [u_group_base, u_group_end).
uniform uint u_group_base;
uniform uint u_group_end;

#ifdef OSL_BLOCK_LIST
layout(std430, binding = SB_SSBO_OSL_BLOCK_TILE) readonly buffer BlockTile { uint block_instance[]; };
layout(std430, binding = SB_SSBO_OSL_LIST) readonly buffer List { uvec2 list[]; };
layout(std430, binding = SB_SSBO_OSL_STATS) readonly buffer Stats { uvec4 dispatch; };
uniform int u_blocks_x; // the atlas's width in blocks
#endif

void main()
{
#ifdef OSL_BLOCK_LIST
    // Whole: u_group_base 0, u_group_end past every slot; in ranges where
    // the harness slices (gpu_dispatch_indirect, daemon/gpu/budget.h).
    uint slot = u_group_base + gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    if (slot >= dispatch.w || slot >= u_group_end)
        return;
    uvec2 entry = list[slot];
    int instance = int(block_instance[entry.x]);
    ivec4 tile = tiles[instance];
    ivec2 atlas_block = ivec2(int(entry.x) % u_blocks_x, int(entry.x) / u_blocks_x);
    ivec2 texel = atlas_block * 8 - tile.xy + ivec2(gl_LocalInvocationID.xy);
    int light_row = int(entry.y);
#else
    uint group = u_group_base + gl_WorkGroupID.y * uint(u_groups_x) + gl_WorkGroupID.x;
    int lo = 0, hi = u_work_count - 1;
    if (u_work_count == 0 || group >= u_group_end ||
        group >= work[hi].z + work[hi].w * work[hi].w)
        return;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (work[mid].z <= group)
            lo = mid;
        else
            hi = mid - 1;
    }
    uvec4 w = work[lo];
    int instance = int(w.x);
    uint local_block = group - w.z;
    ivec2 texel = ivec2(local_block % w.w, local_block / w.w) * 8 + ivec2(gl_LocalInvocationID.xy);
    ivec4 tile = tiles[instance];
    int light_row = int(w.y);
#endif

    Instance inst = instances[instance];
    ivec2 geo = ivec2(tile.w & 0xffff, tile.w >> 16) + texel;
    vec4 p = texelFetch(u_position, geo, 0);
    vec4 n = texelFetch(u_normal, geo, 0);
    vec3 color = vec3(0.0);
    if (p.w > 0.0) {
        vec3 world = inst.pos_scale.xyz + inst.pos_scale.w * p.xyz;
#if defined(SCENE_TEXTURED)
        color = shade_baked(world, normalize(n.xyz), n.w, texelFetch(u_albedo, geo, 0),
                            texelFetch(u_surface, geo, 0), light_row);
#else
        color = shade_all_lights(world, normalize(n.xyz), instance_material(instance), light_row);
#endif
    }
    imageStore(u_atlas, tile.xy + texel, vec4(color, 1.0));
}
