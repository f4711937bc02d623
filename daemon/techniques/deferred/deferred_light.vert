// Deferred, per-light step: instance i covers the pixels light i may touch,
// as DEFERRED_BOUNDS_* chooses: the tight or loose screen rectangle (two
// triangles, the scissor rectangle drawn rather than set, so that one draw
// covers every light), the light's sphere (back faces of a 16 x 8 latitude-
// longitude mesh made from gl_VertexID, scaled to enclose the true sphere),
// or the whole screen. A spot light's bound is its cone's bounding sphere
// (light_shape.glsl); a directional light's is the whole screen whatever the
// option (in the volume mode a screen-filling quad wound to face away, which
// the front-face culling keeps).
#include "light_bounds.glsl"
#include "light_shape.glsl"
flat out int v_light;

const int SPHERE_SEGMENTS = 16, SPHERE_RINGS = 8;

void main()
{
    int i = gl_InstanceID;
    v_light = i;
    vec3 world;
    float r;
    bool bounded = light_bound_sphere(i, light_positions[i].xyz, world, r);
#if defined(DEFERRED_BOUNDS_VOLUME)
    if (!bounded) {
        // Clockwise: a back face, kept by glCullFace(GL_FRONT); the rest of
        // the mesh's vertices collapse to a point.
        const vec2 quad[6] = vec2[6](vec2(-1, -1), vec2(1, 1), vec2(1, -1), vec2(-1, -1),
                                     vec2(-1, 1), vec2(1, 1));
        gl_Position = vec4(gl_VertexID < 6 ? quad[gl_VertexID] : vec2(0.0), 0.0, 1.0);
        return;
    }
    // Quad q of the mesh, corner k of its two triangles (counter-clockwise seen
    // from outside, so culling front faces keeps the far side).
    int q = gl_VertexID / 6, k = gl_VertexID % 6;
    int seg = q % SPHERE_SEGMENTS, ring = q / SPHERE_SEGMENTS;
    const ivec2 corner[6] = ivec2[6](ivec2(0, 0), ivec2(1, 0), ivec2(1, 1), ivec2(0, 0),
                                     ivec2(1, 1), ivec2(0, 1));
    float phi = 6.28318530718 * float(seg + corner[k].x) / float(SPHERE_SEGMENTS);
    float theta = 3.14159265359 * float(ring + corner[k].y) / float(SPHERE_RINGS);
    vec3 dir = vec3(sin(theta) * cos(phi), cos(theta), sin(theta) * sin(phi));
    // Flat facets cut inside the sphere by at most 1 - cos(half the widest
    // facet's diagonal angle), about 3.9% here: grow the mesh by 6%.
    gl_Position = u_frame.view_proj * vec4(world + 1.06 * r * dir, 1.0);
#else
    ivec4 rect;
    if (!bounded)
        rect = ivec4(0, 0, ivec2(u_frame.viewport.xy));
    else
#if defined(DEFERRED_BOUNDS_FULLSCREEN)
    rect = ivec4(0, 0, ivec2(u_frame.viewport.xy));
#elif defined(DEFERRED_BOUNDS_SCISSOR_LOOSE)
    rect = light_rect(LIGHT_RECT_LOOSE, world, r);
#else
    rect = light_rect(LIGHT_RECT_TIGHT, world, r);
#endif
    const ivec2 corner[6] = ivec2[6](ivec2(0, 0), ivec2(1, 0), ivec2(1, 1), ivec2(0, 0),
                                     ivec2(1, 1), ivec2(0, 1));
    ivec2 c = corner[gl_VertexID % 6];
    vec2 p = vec2(c.x == 0 ? rect.x : rect.z, c.y == 0 ? rect.y : rect.w);
    // An empty rectangle collapses to a point: no fragments.
    if (rect.x >= rect.z || rect.y >= rect.w)
        p = vec2(0.0);
    gl_Position = vec4(p * u_frame.viewport.zw * 2.0 - 1.0, 0.0, 1.0);
#endif
}
