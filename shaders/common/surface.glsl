// Asset materials (scenes from glTF assets: the harness defines
// SCENE_TEXTURED for every program when the scene comes from an asset).
// Fragment shaders that draw scene meshes include this file; without
// SCENE_TEXTURED it declares nothing, so the procedural scenes' programs
// are the same text as before.
//
// A material is one SurfaceMaterial in the material buffer (written by
// daemon/gpu/gpu_scene.c: materials_init) and up to five textures on the
// SB_TEX_MATERIAL_* units, which gpu_scene_draw binds with their samplers
// before each asset mesh's draw, with u_material its row. The entry points:
//   material_surface_grad(row, uvs, duvdx, duvdy, N, tangent, front): the
//     surface at any point given its uv0 (uvs.xy), uv1 (uvs.zw), their
//     screen (or texel) derivatives, which pick the mip level, geometric
//     normal and tangent frame; no discard, no implicit derivatives: what
//     object-space shading would bake a texel with (from a compute shader
//     too, with zero derivatives for the finest level);
//   material_surface(row, uvs, N, tangent, front): the same with the
//     fragment's own derivatives, taken here in uniform control flow (a
//     texture() inside the slots' branches would take them in non-uniform
//     flow, which GLSL leaves undefined: llvmpipe's differ where a draw is
//     scissored into tiles);
//   surface_here(N): the same at this fragment (u_material, the varyings,
//     gl_FrontFacing), discarding where an alpha-masked material's alpha is
//     below its cutoff;
//   surface_alpha_clip(): the mask's discard alone (depth and shadow passes);
//   surface_shade_all_lights(P, s): every light, ambient scaled by occlusion,
//     emissive added after lighting (forward and the transparent pass).
#include "lighting.glsl"

#if defined(SCENE_TEXTURED)
// std430, 64 bytes.
struct SurfaceMaterial {
    vec4 base_color;      // linear RGBA factor
    vec4 emissive_cutoff; // emissive factor (linear), alpha cutoff (mask), else -1
    vec4 params;          // metallic, roughness, normal scale, occlusion strength
    ivec4 slots;          // bit s: slot s has a texture; bit s: slot s reads uv1;
                          // alpha mode (0 opaque, 1 mask, 2 blend); double-sided
};
layout(std430, binding = SB_SSBO_MATERIALS) readonly buffer MaterialBuffer { SurfaceMaterial materials[]; };

// The glTF slots, in enum asset_texture_slot order.
const int SLOT_BASE_COLOR = 0, SLOT_METALLIC_ROUGHNESS = 1, SLOT_NORMAL = 2, SLOT_OCCLUSION = 3,
          SLOT_EMISSIVE = 4;
layout(binding = SB_TEX_MATERIAL_BASE_COLOR) uniform sampler2D u_material_base_color; // sRGB
layout(binding = SB_TEX_MATERIAL_METALLIC_ROUGHNESS) uniform sampler2D u_material_metallic_roughness;
layout(binding = SB_TEX_MATERIAL_NORMAL) uniform sampler2D u_material_normal;
layout(binding = SB_TEX_MATERIAL_OCCLUSION) uniform sampler2D u_material_occlusion;
layout(binding = SB_TEX_MATERIAL_EMISSIVE) uniform sampler2D u_material_emissive; // sRGB
layout(location = SB_LOC_MATERIAL) uniform int u_material;

in vec4 v_tex;     // uv0 (xy), uv1 (zw): scene.vert
in vec4 v_tangent; // world-space tangent, handedness in w

bool material_has(SurfaceMaterial sm, int slot)
{
    return (sm.slots.x & (1 << slot)) != 0;
}

// What the lighting library's Material does not carry.
struct TexturedSurface {
    Material m;
    vec3 N;         // shading normal: normal-mapped, facing the viewer on double-sided back faces
    vec3 emissive;  // linear, added after lighting
    float occlusion; // scales the ambient (and image-based) term only
    float alpha;
};

// Slot `slot`'s texel: its uv set and that set's derivatives.
#define MATERIAL_SAMPLE(sampler_, sm, slot, uvs, dx, dy)                                   \
    ((sm.slots.y & (1 << (slot))) != 0 ? textureGrad(sampler_, (uvs).zw, (dx).zw, (dy).zw) \
                                       : textureGrad(sampler_, (uvs).xy, (dx).xy, (dy).xy))

float material_alpha(SurfaceMaterial sm, vec4 uvs, vec4 dx, vec4 dy)
{
    float a = sm.base_color.a;
    if (material_has(sm, SLOT_BASE_COLOR))
        a *= MATERIAL_SAMPLE(u_material_base_color, sm, SLOT_BASE_COLOR, uvs, dx, dy).a;
    return a;
}

TexturedSurface material_surface_grad(int row, vec4 uvs, vec4 dx, vec4 dy, vec3 N, vec4 tangent,
                                      bool front)
{
    SurfaceMaterial sm = materials[row];
    TexturedSurface s;
    vec4 base = sm.base_color;
    if (material_has(sm, SLOT_BASE_COLOR))
        base *= MATERIAL_SAMPLE(u_material_base_color, sm, SLOT_BASE_COLOR, uvs, dx, dy);
    float metallic = sm.params.x, roughness = sm.params.y;
    if (material_has(sm, SLOT_METALLIC_ROUGHNESS)) {
        vec4 mr = MATERIAL_SAMPLE(u_material_metallic_roughness, sm, SLOT_METALLIC_ROUGHNESS, uvs, dx, dy);
        roughness *= mr.g; // glTF: roughness in green, metallic in blue
        metallic *= mr.b;
    }
    // A double-sided material's back face is lit as the side it shows.
    float facing = (sm.slots.w != 0 && !front) ? -1.0 : 1.0;
    N *= facing;
    if (material_has(sm, SLOT_NORMAL)) {
        vec3 t = normalize(tangent.xyz - N * dot(N, tangent.xyz));
        vec3 b = cross(N, t) * tangent.w * facing;
        vec3 tn = MATERIAL_SAMPLE(u_material_normal, sm, SLOT_NORMAL, uvs, dx, dy).xyz * 2.0 - 1.0;
        tn.xy *= sm.params.z;
        N = normalize(t * tn.x + b * tn.y + N * tn.z);
    }
    s.N = N;
    s.occlusion = 1.0;
    if (material_has(sm, SLOT_OCCLUSION))
        s.occlusion = 1.0 + sm.params.w *
                                (MATERIAL_SAMPLE(u_material_occlusion, sm, SLOT_OCCLUSION, uvs, dx, dy).r - 1.0);
    s.emissive = sm.emissive_cutoff.rgb;
    if (material_has(sm, SLOT_EMISSIVE))
        s.emissive *= MATERIAL_SAMPLE(u_material_emissive, sm, SLOT_EMISSIVE, uvs, dx, dy).rgb;
    // Phong's terms from roughness, as daemon/scene/scene_asset.c sets the
    // constant fallback: Beckmann's exponent, a dielectric's 4% or a metal's.
    s.m = Material(base.rgb, 0.04 + 0.96 * metallic,
                   max(1.0, 2.0 / max(roughness * roughness, 1e-3) - 2.0), metallic, roughness);
    s.alpha = base.a;
    return s;
}

TexturedSurface material_surface(int row, vec4 uvs, vec3 N, vec4 tangent, bool front)
{
    return material_surface_grad(row, uvs, dFdx(uvs), dFdy(uvs), N, tangent, front);
}

TexturedSurface surface_here(vec3 N)
{
    TexturedSurface s = material_surface(u_material, v_tex, N, v_tangent, gl_FrontFacing);
    if (s.alpha < materials[u_material].emissive_cutoff.w)
        discard;
    return s;
}

void surface_alpha_clip()
{
    SurfaceMaterial sm = materials[u_material];
    vec4 dx = dFdx(v_tex), dy = dFdy(v_tex);
    if (sm.emissive_cutoff.w >= 0.0 && material_alpha(sm, v_tex, dx, dy) < sm.emissive_cutoff.w)
        discard;
}

vec3 surface_shade_all_lights(vec3 P, TexturedSurface s)
{
    vec3 V = normalize(u_frame.eye.xyz - P);
    vec3 color = s.occlusion * light_ambient(s.m, P, s.N, V);
    for (int i = 0; i < u_frame.counts.y; i++)
        color += light_contribution(i, light_position(i, 0), P, s.N, V, s.m);
    return color + s.emissive;
}
#endif
