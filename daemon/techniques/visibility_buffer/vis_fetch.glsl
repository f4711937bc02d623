// The visibility buffer's reading side: a pixel's ids, the triangle's
// vertices fetched from the technique's copy of every mesh (the same
// vertex layout as the scene's buffers, daemon/scene/mesh.h), and its
// attributes rebuilt at the pixel's centre with perspective-correct
// barycentrics, as the rasteriser interpolates them for forward (at the
// centre at MSAA too, as forward's non-centroid inputs are), with their
// screen derivatives taken as a 2x2 quad takes them (for the material's
// mip levels).
#include "frame.glsl"
#include "scene_data.glsl"

// std430, 96 bytes: struct mesh_vertex as six vec4s: pos.xyz normal.x |
// normal.yz uv | chart | tex (TEXCOORD_0, TEXCOORD_1) | tangent | colour.
struct VisVertex {
    vec4 a, b, chart, tex, tangent, color;
};
layout(std430, binding = SB_SSBO_VIS_VERTICES) readonly buffer VisVertices { VisVertex vis_vertices[]; };
layout(std430, binding = SB_SSBO_VIS_INDICES) readonly buffer VisIndices { uint vis_indices[]; };
// Per mesh: its first index, first vertex, material row (-1: the instance's
// own material) and material key (the window depth times 65536 its pixels
// are classified at; 0 without materials).
layout(std430, binding = SB_SSBO_VIS_MESHES) readonly buffer VisMeshes { ivec4 vis_meshes[]; };

#if defined(SB_MSAA_SAMPLES)
layout(binding = SB_TEX_GBUFFER0) uniform usampler2DMS u_ids;
#define VIS_FETCH(pixel, which) texelFetch(u_ids, pixel, which)
#else
layout(binding = SB_TEX_GBUFFER0) uniform usampler2D u_ids;
#define VIS_FETCH(pixel, which) texelFetch(u_ids, pixel, 0)
#endif

// The stored id (both words; 0 where nothing was drawn).
uvec2 vis_raw(ivec2 pixel, int which)
{
    return VIS_FETCH(pixel, which).xy;
}

bool vis_ids(ivec2 pixel, int which, out int instance, out int triangle)
{
    uvec2 t = vis_raw(pixel, which);
    instance = -1;
    triangle = 0;
    if (t.x == 0u)
        return false;
#if defined(VIS_WIDE)
    instance = int(t.x) - 1;
    triangle = int(t.y);
#else
    instance = int(t.x >> uint(VIS_TRIANGLE_BITS)) - 1;
    triangle = int(t.x & ((1u << uint(VIS_TRIANGLE_BITS)) - 1u));
#endif
    return true;
}

struct VisSurface {
    int instance, mesh;
    vec3 P;          // world position
    vec3 N;          // interpolated normal, normalised
    vec4 tex;        // TEXCOORD_0, TEXCOORD_1
    vec4 dtex_dx, dtex_dy;
    vec4 tangent;
    vec4 color;      // COLOR_0 (white where the mesh has none)
    bool front;      // counter-clockwise on screen, as glFrontFace(GL_CCW)
};

// Perspective-correct barycentrics of the pixel at ndc, from the
// triangle's edge vectors in homogeneous 2D (Olano and Greer 1997): the
// point sum b_i (x_i, y_i, w_i) lies on the pixel's ray (ndc, 1), so b is
// proportional to (e0 . p, e1 . p, e2 . p) with e0 = c1 x c2 and so on.
// Valid whatever the vertices' w (a triangle reaching behind the eye,
// which the rasteriser clipped), and extrapolated outside the triangle.
vec3 vis_barycentrics(vec2 ndc, mat3 e)
{
    vec3 b = vec3(ndc, 1.0) * e;
    return b / (b.x + b.y + b.z);
}

bool vis_surface(ivec2 pixel, int which, out VisSurface s)
{
    int triangle;
    if (!vis_ids(pixel, which, s.instance, triangle))
        return false;
    Instance inst = instances[s.instance];
    s.mesh = int(inst.albedo_mesh.w);
    ivec4 m = vis_meshes[s.mesh];
    int first = m.x + 3 * triangle;
    VisVertex v0 = vis_vertices[int(vis_indices[first]) + m.y];
    VisVertex v1 = vis_vertices[int(vis_indices[first + 1]) + m.y];
    VisVertex v2 = vis_vertices[int(vis_indices[first + 2]) + m.y];
    // World positions exactly as scene.vert computes them, projected by the
    // same matrix: the triangle the rasteriser drew.
    vec3 w0 = inst.pos_scale.xyz + inst.pos_scale.w * v0.a.xyz;
    vec3 w1 = inst.pos_scale.xyz + inst.pos_scale.w * v1.a.xyz;
    vec3 w2 = inst.pos_scale.xyz + inst.pos_scale.w * v2.a.xyz;
    vec4 c0 = u_frame.view_proj * vec4(w0, 1.0);
    vec4 c1 = u_frame.view_proj * vec4(w1, 1.0);
    vec4 c2 = u_frame.view_proj * vec4(w2, 1.0);
    vec3 h0 = c0.xyw, h1 = c1.xyw, h2 = c2.xyw;
    mat3 e = mat3(cross(h1, h2), cross(h2, h0), cross(h0, h1)); // columns: b = p * e
    vec2 px = 2.0 * u_frame.viewport.zw; // one pixel in NDC
    vec2 centre = (vec2(pixel) + 0.5) * px - 1.0;
    vec3 b = vis_barycentrics(centre, e);
    // The quad's derivatives: across its lower row and up its left column.
    vec2 corner = (vec2(pixel & ivec2(~1)) + 0.5) * px - 1.0;
    vec3 b00 = vis_barycentrics(corner, e);
    vec3 dbx = vis_barycentrics(corner + vec2(px.x, 0.0), e) - b00;
    vec3 dby = vis_barycentrics(corner + vec2(0.0, px.y), e) - b00;
    s.P = b.x * w0 + b.y * w1 + b.z * w2;
    s.N = normalize(b.x * vec3(v0.a.w, v0.b.xy) + b.y * vec3(v1.a.w, v1.b.xy) +
                    b.z * vec3(v2.a.w, v2.b.xy));
    s.tex = b.x * v0.tex + b.y * v1.tex + b.z * v2.tex;
    s.dtex_dx = dbx.x * v0.tex + dbx.y * v1.tex + dbx.z * v2.tex;
    s.dtex_dy = dby.x * v0.tex + dby.y * v1.tex + dby.z * v2.tex;
    s.tangent = b.x * v0.tangent + b.y * v1.tangent + b.z * v2.tangent;
    // COLOR_0 interpolated as scene.vert passes it, less 1, and the 1 added
    // back: a mesh without it comes out exactly white (surface.glsl).
    s.color = (b.x * (v0.color - 1.0) + b.y * (v1.color - 1.0) + b.z * (v2.color - 1.0)) + 1.0;
    // Facing: the sign of det(h0, h1, h2), the projected area times the
    // three w's (the rasteriser's, for the part it kept).
    s.front = dot(h0, e[0]) > 0.0;
    return true;
}
