// OSL lighting pass: one 8x8 block of one object's tile per work group. The
// work list holds one entry per object to shade: (instance, light row,
// first block, blocks per tile row); a group finds its entry by binary search.
// With OSL_BLOCK_LIST (osl.visibility "seen") the groups come from an
// indirect dispatch over the blocks osl_select.comp listed: (atlas block,
// light row) each.
#include "lighting.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

#ifdef OSL_CULL
// Per block, the lights that reach it (auto tiles): the covered texels'
// bounding sphere against each point and spot light's sphere, a bit per
// light. A light left out reaches none of the block's texels, where its
// contribution is exactly 0, and the others are summed in light order, so
// a texel's sum is the one over every light. Beyond OSL_CULL_WORDS * 32
// lights every light is kept.
const int OSL_CULL_WORDS = 128;
shared uint s_mask[OSL_CULL_WORDS];
shared vec4 s_pos[64]; // world position, w: covered
shared vec4 s_bound;   // centre, radius (negative: nothing covered)

void cull_lights(vec3 P, bool covered, int row)
{
    uint li = gl_LocalInvocationIndex;
    s_pos[li] = vec4(P, covered ? 1.0 : 0.0);
    for (uint k = li; k < uint(OSL_CULL_WORDS); k += 64u)
        s_mask[k] = 0u;
    barrier();
    if (li == 0u) {
        vec3 lo = vec3(1e30), hi = vec3(-1e30);
        for (int k = 0; k < 64; k++)
            if (s_pos[k].w > 0.0) {
                lo = min(lo, s_pos[k].xyz);
                hi = max(hi, s_pos[k].xyz);
            }
        s_bound = all(lessThanEqual(lo, hi)) ? vec4(0.5 * (lo + hi), 0.5 * length(hi - lo)) : vec4(0.0, 0.0, 0.0, -1.0);
    }
    barrier();
    int count = u_frame.counts.y;
    if (s_bound.w >= 0.0)
        for (int i = int(li); i < count; i += 64) {
            bool keep = i >= OSL_CULL_WORDS * 32 || light_type(i) == LIGHT_DIRECTIONAL;
            if (!keep) {
                float reach = lights[i].color_radius.w + s_bound.w;
                keep = distance(light_position(i, row), s_bound.xyz) < reach * 1.0001 + 1e-4;
            }
            if (keep && i < OSL_CULL_WORDS * 32)
                atomicOr(s_mask[i >> 5], 1u << uint(i & 31));
        }
    barrier();
}

// The lights that reach the block, in order (every light beyond the mask's).
#define FOR_EACH_LIGHT(i)                                                                   \
    for (int w_ = 0; w_ * 32 < u_frame.counts.y; w_++)                                      \
        for (uint b_ = w_ < OSL_CULL_WORDS ? s_mask[w_] : 0xffffffffu; b_ != 0u; b_ &= b_ - 1u) { \
            int i = w_ * 32 + findLSB(b_);                                                  \
            if (i >= u_frame.counts.y)                                                      \
                break;
#else
#define FOR_EACH_LIGHT(i) for (int i = 0; i < u_frame.counts.y; i++) {
#endif


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
    FOR_EACH_LIGHT(i)
        color += light_contribution(i, light_position(i, row), P, N, V, m);
    }
    return color + surface.rgb;
}
#endif
// With levels (resolution "auto"), each tile's coarser levels lie below
// the atlas's level 0 (u_atlas_w x u_atlas_h0), as osl_level_origin (osl_gl.h)
// places them, and the geometry atlas's likewise (u_geo_size0).
uniform int u_atlas_w;
uniform int u_atlas_h0;
uniform ivec2 u_geo_size0;

ivec2 level_origin(int l, ivec2 size0)
{
    return l == 0 ? ivec2(0) : ivec2(size0.x - (size0.x >> (l - 1)), size0.y);
}

#if defined(OSL_SPLIT)
// Asset scenes under Phong and Blinn-Phong, which are linear in the base
// colour: the atlas holds the diffuse light (for a white base colour) and
// this plane the specular light, and the raster pass multiplies the base
// colour in at each pixel from the material's own textures, as forward
// does, so that texture detail finer than the texels stays sharp.
layout(rgba16f, binding = SB_IMG_OSL_ATLAS_SPECULAR) writeonly uniform image2D u_atlas_specular;

// light_contribution's (lighting.glsl) terms, apart (light_reach its
// falloff, the presets' window or glTF's inverse square): diffuse += C att N.L,
// specular += C att spec s; the base colour left out. The diffuse light is
// written as a function of the normal, so that the raster pass applies the
// pixel's own normal-mapped normal as forward does: dir = sum of mean(C att) L
// over the lights that face the texel's normal (diffuse = 3 chroma max(N.dir, 0)
// with chroma the diffuse light's share per channel, exact at the texel's
// normal). Normal-map detail finer than the texels (the court's bricks at
// 160x120: lighting that changes every 2 to 3 pixels) then stays sharp.
void shade_split(vec3 P, vec3 N, float metallic, vec4 albedo, int row, out vec3 diffuse,
                 out vec3 specular, out vec3 dir)
{
    bool two_sided = albedo.a >= 2.0;
    float roughness = albedo.a - (two_sided ? 2.0 : 0.0);
    float spec = 0.04 + 0.96 * metallic;
    float shininess = max(1.0, 2.0 / max(roughness * roughness, 1e-3) - 2.0);
    vec3 V = normalize(u_frame.eye.xyz - P);
    if (two_sided && dot(N, V) < 0.0)
        N = -N;
    diffuse = vec3(0.0);
    specular = vec3(0.0);
    dir = vec3(0.0);
    FOR_EACH_LIGHT(i)
        int type = light_type(i);
        vec3 L;
        float att = light_reach(i, light_position(i, row), P, L);
        if (att <= 0.0)
            continue;
        float nl = dot(N, L);
        if (nl <= 0.0)
            continue;
#if defined(LOOK_SHADOWS)
        if (type == LIGHT_DIRECTIONAL)
            att *= shadow_sun_visibility(i, P, N);
        else
            att *= shadow_visibility(i, P, N, nl);
#endif
#if defined(LIGHTING_BLINN_PHONG)
        float s = pow(max(dot(N, normalize(L + V)), 0.0), shininess);
#else
        float s = pow(max(dot(reflect(-L, N), V), 0.0), shininess);
#endif
        vec3 c = lights[i].color_radius.rgb * att;
        diffuse += c * nl;
        dir += ((c.r + c.g + c.b) / 3.0) * L;
        specular += c * (spec * s);
    }
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
    uint owner = block_instance[entry.x];
    int instance = int(owner & 0xffffffu), level = int(owner >> 24);
    ivec4 tile = tiles[instance];
    ivec2 tile_at = level_origin(level, ivec2(u_atlas_w, u_atlas_h0)) + (tile.xy >> level);
    ivec2 atlas_block = ivec2(int(entry.x) % u_blocks_x, int(entry.x) / u_blocks_x);
    ivec2 texel = atlas_block * 8 - tile_at + ivec2(gl_LocalInvocationID.xy);
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
    int instance = int(w.x & 0xffffffu), level = int(w.x >> 24);
    uint local_block = group - w.z;
    ivec2 texel = ivec2(local_block % w.w, local_block / w.w) * 8 + ivec2(gl_LocalInvocationID.xy);
    ivec4 tile = tiles[instance];
    ivec2 tile_at = level_origin(level, ivec2(u_atlas_w, u_atlas_h0)) + (tile.xy >> level);
    int light_row = int(w.y);
#endif

    Instance inst = instances[instance];
    ivec2 geo = level_origin(level, u_geo_size0) + (ivec2(tile.w & 0xffff, tile.w >> 16) >> level) +
                texel;
    vec4 p = texelFetch(u_position, geo, 0);
    vec4 n = texelFetch(u_normal, geo, 0);
    vec3 color = vec3(0.0);
#ifdef OSL_CULL
    cull_lights(inst.pos_scale.xyz + inst.pos_scale.w * p.xyz, p.w > 0.0, light_row);
#endif
#if defined(OSL_SPLIT)
    // u_atlas: the diffuse light's direction (xyz) and the red share of its
    // colour (w); the specular plane: the specular light (rgb) and the green
    // share (a). See shade_split.
    vec3 specular = vec3(0.0), dir = vec3(0.0);
    if (p.w > 0.0)
        shade_split(inst.pos_scale.xyz + inst.pos_scale.w * p.xyz, normalize(n.xyz), n.w,
                    texelFetch(u_albedo, geo, 0), light_row, color, specular, dir);
    float sum = color.r + color.g + color.b;
    vec2 chroma = sum > 0.0 ? color.rg / sum : vec2(1.0 / 3.0);
    imageStore(u_atlas_specular, tile_at + texel, vec4(specular, chroma.g));
    imageStore(u_atlas, tile_at + texel, vec4(dir, chroma.r));
#else
    if (p.w > 0.0) {
        vec3 world = inst.pos_scale.xyz + inst.pos_scale.w * p.xyz;
#if defined(SCENE_TEXTURED)
        color = shade_baked(world, normalize(n.xyz), n.w, texelFetch(u_albedo, geo, 0),
                            texelFetch(u_surface, geo, 0), light_row);
#elif defined(OSL_CULL)
        // shade_all_lights (lighting.glsl) over the lights that reach the block
        vec3 N = normalize(n.xyz), V = normalize(u_frame.eye.xyz - world);
        Material m = instance_material(instance);
        color = light_ambient(m, world, N, V);
        FOR_EACH_LIGHT(i)
            color += light_contribution(i, light_position(i, light_row), world, N, V, m);
        }
#else
        color = shade_all_lights(world, normalize(n.xyz), instance_material(instance), light_row);
#endif
    }
    imageStore(u_atlas, tile_at + texel, vec4(color, 1.0));
#endif
}
