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
//   material_surface_grad(row, uvs, duvdx, duvdy, N, tangent, front[, color]):
//     the surface at any point given the file's uv sets, TEXCOORD_0 (uvs.xy)
//     and TEXCOORD_1 (uvs.zw), their screen (or texel) derivatives, which
//     pick the mip level, geometric normal, tangent frame and COLOR_0 (white
//     where left out); each texture reads the set its material names,
//     through its KHR_texture_transform; no discard, no implicit
//     derivatives: what object-space shading would bake a texel with (from
//     a compute shader too, with zero derivatives for the finest level);
//   material_surface(row, uvs, N, tangent, front[, color]): the same with
//     the fragment's own derivatives, taken here in uniform control flow (a
//     texture() inside the slots' branches would take them in non-uniform
//     flow, which GLSL leaves undefined: llvmpipe's differ where a draw is
//     scissored into tiles);
//   surface_here(N): the same at this fragment (u_material, the varyings,
//     gl_FrontFacing), discarding where an alpha-masked material's alpha is
//     below its cutoff;
//   surface_alpha_clip(): the mask's discard alone (depth and shadow passes);
//   surface_shade_all_lights(P, s): every light, ambient scaled by occlusion,
//     emissive added after lighting (forward and the transparent pass);
//   surface_debug_here(N): look.debug's channel at this fragment (programs
//     built with LOOK_DEBUG: daemon/look/debug.c and the transparent pass).
#include "lighting.glsl"

#if defined(SCENE_TEXTURED)
// std430, 224 bytes.
struct SurfaceMaterial {
    vec4 base_color;      // linear RGBA factor
    vec4 emissive_cutoff; // emissive factor (linear), alpha cutoff (mask), else -1
    vec4 params;          // metallic, roughness, normal scale, occlusion strength
    ivec4 slots;          // bit s: slot s has a texture; bit s: slot s reads TEXCOORD_1;
                          // alpha mode (0 opaque, 1 mask, 2 blend); double-sided
    // Slot s's KHR_texture_transform: uv' = (dot(t[2s].xyz, (uv, 1)),
    // dot(t[2s + 1].xyz, (uv, 1))).
    vec4 uv_transform[10];
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

// SURFACE_NO_VARYINGS: a program that rebuilds the attributes itself (the
// visibility buffer's shading) reads none of the vertex stage's, and gets
// material_surface_grad and surface_shade_all_lights alone.
#if !defined(SURFACE_NO_VARYINGS)
in vec4 v_tex;     // TEXCOORD_0 (xy), TEXCOORD_1 (zw): scene.vert
in vec4 v_tangent; // world-space tangent, handedness in w
#endif
#if defined(SURFACE_VERTEX_COLOR)
// COLOR_0, linear (white where the mesh has none): programs whose vertex
// stage passes it (scene.vert, shadow.vert, OSL's texgen and draw) define
// SURFACE_VERTEX_COLOR before including this file; the others shade
// without it. It
// travels as COLOR_0 - 1: perspective-correct interpolation of a constant
// is not exact, and white would come out a rounding below 1 (a mesh
// without COLOR_0 drew differently from before it existed); 0 is exact.
in vec4 v_color;
#define SURFACE_COLOR (v_color + 1.0)
#else
#define SURFACE_COLOR vec4(1.0)
#endif

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
    // What look.debug shows beside them (surface_debug_here): the tangent
    // frame (turned with the face the eye sees), the normal map's texel
    // unpacked and scaled (0 without one) and the occlusion map's red (1
    // without one), strength not applied.
    vec3 T, B;
    vec3 normal_texel;
    float occlusion_texel;
};

// Slot `slot`'s coordinates: its uv set through its transform.
vec2 material_uv(SurfaceMaterial sm, int slot, vec4 uvs)
{
    vec3 uv = vec3((sm.slots.y & (1 << slot)) != 0 ? uvs.zw : uvs.xy, 1.0);
    return vec2(dot(sm.uv_transform[2 * slot].xyz, uv), dot(sm.uv_transform[2 * slot + 1].xyz, uv));
}

// The same for a derivative (no translation).
vec2 material_duv(SurfaceMaterial sm, int slot, vec4 d)
{
    vec2 duv = (sm.slots.y & (1 << slot)) != 0 ? d.zw : d.xy;
    return vec2(dot(sm.uv_transform[2 * slot].xy, duv), dot(sm.uv_transform[2 * slot + 1].xy, duv));
}

// Slot `slot`'s texel: its uv set, transformed, and that set's derivatives.
#define MATERIAL_SAMPLE(sampler_, sm, slot, uvs, dx, dy)                               \
    textureGrad(sampler_, material_uv(sm, slot, uvs), material_duv(sm, slot, dx), \
                material_duv(sm, slot, dy))

float material_alpha(SurfaceMaterial sm, vec4 uvs, vec4 dx, vec4 dy)
{
    float a = sm.base_color.a;
    if (material_has(sm, SLOT_BASE_COLOR))
        a *= MATERIAL_SAMPLE(u_material_base_color, sm, SLOT_BASE_COLOR, uvs, dx, dy).a;
    return a;
}

TexturedSurface material_surface_grad(int row, vec4 uvs, vec4 dx, vec4 dy, vec3 N, vec4 tangent,
                                      bool front, vec4 color)
{
    SurfaceMaterial sm = materials[row];
    TexturedSurface s;
    vec4 base = sm.base_color * color;
    if (material_has(sm, SLOT_BASE_COLOR))
        base *= MATERIAL_SAMPLE(u_material_base_color, sm, SLOT_BASE_COLOR, uvs, dx, dy);
    float metallic = sm.params.x, roughness = sm.params.y;
    if (material_has(sm, SLOT_METALLIC_ROUGHNESS)) {
        vec4 mr = MATERIAL_SAMPLE(u_material_metallic_roughness, sm, SLOT_METALLIC_ROUGHNESS, uvs, dx, dy);
        roughness *= mr.g; // glTF: roughness in green, metallic in blue
        metallic *= mr.b;
    }
    // The tangent frame as the vertices give it, turned with the face.
    vec3 t0 = normalize(tangent.xyz - N * dot(N, tangent.xyz));
    vec3 b0 = cross(N, t0) * tangent.w;
    s.T = front ? t0 : -t0;
    s.B = front ? b0 : -b0;
    s.normal_texel = vec3(0.0);
    if (material_has(sm, SLOT_NORMAL)) {
        vec3 tn = MATERIAL_SAMPLE(u_material_normal, sm, SLOT_NORMAL, uvs, dx, dy).xyz * 2.0 - 1.0;
        tn.xy *= sm.params.z;
        s.normal_texel = normalize(tn);
        N = normalize(t0 * tn.x + b0 * tn.y + N * tn.z);
    }
    // A double-sided material's back face is lit as the side it shows:
    // glTF reverses its normal, the normal-mapped one whole (a bump on the
    // front is a dent behind).
    if (sm.slots.w != 0 && !front)
        N = -N;
    s.N = N;
    s.occlusion = 1.0;
    s.occlusion_texel = 1.0;
    if (material_has(sm, SLOT_OCCLUSION)) {
        s.occlusion_texel = MATERIAL_SAMPLE(u_material_occlusion, sm, SLOT_OCCLUSION, uvs, dx, dy).r;
        s.occlusion = 1.0 + sm.params.w * (s.occlusion_texel - 1.0);
    }
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

TexturedSurface material_surface_grad(int row, vec4 uvs, vec4 dx, vec4 dy, vec3 N, vec4 tangent,
                                      bool front)
{
    return material_surface_grad(row, uvs, dx, dy, N, tangent, front, vec4(1.0));
}

TexturedSurface material_surface(int row, vec4 uvs, vec3 N, vec4 tangent, bool front, vec4 color)
{
    return material_surface_grad(row, uvs, dFdx(uvs), dFdy(uvs), N, tangent, front, color);
}

TexturedSurface material_surface(int row, vec4 uvs, vec3 N, vec4 tangent, bool front)
{
    return material_surface(row, uvs, N, tangent, front, vec4(1.0));
}

#if !defined(SURFACE_NO_VARYINGS)
TexturedSurface surface_here(vec3 N)
{
    TexturedSurface s = material_surface(u_material, v_tex, N, v_tangent, gl_FrontFacing, SURFACE_COLOR);
    if (s.alpha < materials[u_material].emissive_cutoff.w)
        discard;
    return s;
}

void surface_alpha_clip()
{
    SurfaceMaterial sm = materials[u_material];
    vec4 dx = dFdx(v_tex), dy = dFdy(v_tex);
    if (sm.emissive_cutoff.w >= 0.0 &&
        SURFACE_COLOR.a * material_alpha(sm, v_tex, dx, dy) < sm.emissive_cutoff.w)
        discard;
}

#if defined(LOOK_DEBUG)
// look.debug (daemon/lighting/look_spec.h, docs/api.md): one channel of
// the surface, encoded as the Khronos glTF Sample Viewer writes its debug
// output of that name (its pbr.frag), so that the two images compare
// directly: directions n * 0.5 + 0.5, colours gamma 2.2 (its linearTosRGB),
// the rest as they are; written raw (the resolve applies no exposure or
// tone curve to a debug job). Masked materials are not cut and blended
// ones are drawn opaque, as the viewer draws its debug outputs.
layout(location = SB_LOC_MESH_ATTRIBUTES) uniform int u_mesh_attributes; // bit 0 TEXCOORD_0, bit 1 TEXCOORD_1

// Where the channel has nothing to show (no such map or uv set): the
// viewer's grey checks, 25 pixels a side.
vec3 debug_checks()
{
    vec2 f = fract(0.02 * gl_FragCoord.xy);
    vec2 a = step(0.5, f), b = step(0.5, vec2(1.0) - f);
    return vec3(0.9 + a.x * a.y + b.x * b.y);
}

vec3 debug_gamma(vec3 c)
{
    return pow(max(c, vec3(0.0)), vec3(1.0 / 2.2));
}

// The channel at this fragment; N the interpolated vertex normal.
vec3 surface_debug_here(vec3 N)
{
    SurfaceMaterial sm = materials[u_material];
    TexturedSurface s = material_surface(u_material, v_tex, N, v_tangent, gl_FrontFacing, SURFACE_COLOR);
    vec3 ng = gl_FrontFacing ? N : -N;
#if defined(LOOK_DEBUG_SHADING_NORMAL)
    return s.N * 0.5 + 0.5;
#elif defined(LOOK_DEBUG_GEOMETRIC_NORMAL)
    return ng * 0.5 + 0.5;
#elif defined(LOOK_DEBUG_NORMAL_TEXTURE)
    return material_has(sm, SLOT_NORMAL) ? s.normal_texel * 0.5 + 0.5 : debug_checks();
#elif defined(LOOK_DEBUG_TANGENT)
    return s.T * 0.5 + 0.5;
#elif defined(LOOK_DEBUG_BITANGENT)
    return s.B * 0.5 + 0.5;
#elif defined(LOOK_DEBUG_BASE_COLOR)
    return debug_gamma(s.m.albedo);
#elif defined(LOOK_DEBUG_METALLIC)
    return vec3(clamp(s.m.metallic, 0.0, 1.0));
#elif defined(LOOK_DEBUG_ROUGHNESS)
    return vec3(clamp(s.m.roughness, 0.0, 1.0));
#elif defined(LOOK_DEBUG_OCCLUSION)
    return material_has(sm, SLOT_OCCLUSION) ? vec3(s.occlusion_texel) : debug_checks();
#elif defined(LOOK_DEBUG_EMISSIVE)
    return debug_gamma(s.emissive);
#elif defined(LOOK_DEBUG_UV0)
    return (u_mesh_attributes & 1) != 0 ? vec3(v_tex.xy, 0.0) : debug_checks();
#elif defined(LOOK_DEBUG_UV1)
    return (u_mesh_attributes & 2) != 0 ? vec3(v_tex.zw, 0.0) : debug_checks();
#elif defined(LOOK_DEBUG_ALPHA)
    return vec3(sm.slots.z == 0 ? 1.0 : s.alpha);
#else
    return debug_checks();
#endif
}
#endif
#endif // !SURFACE_NO_VARYINGS

vec3 surface_shade_all_lights(vec3 P, TexturedSurface s)
{
    vec3 V = normalize(u_frame.eye.xyz - P);
    vec3 color = s.occlusion * light_ambient(s.m, P, s.N, V);
    for (int i = 0; i < u_frame.counts.y; i++)
        color += light_contribution(i, light_position(i, 0), P, s.N, V, s.m);
    return color + s.emissive;
}
#endif
