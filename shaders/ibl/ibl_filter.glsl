// Shared by the probe filters: the direction of this fragment's texel in the
// face being written, and the Hammersley set.
#include "cube_faces.glsl"
layout(location = SB_LOC_IBL_FACE) uniform int u_face;
layout(location = SB_LOC_IBL_PARAMS) uniform vec4 u_params; // x: roughness or lod, y: 1 / size, z: samples, w: source size
layout(binding = SB_TEX_IBL_SOURCE) uniform samplerCube u_source;
layout(location = 0) out vec4 out_color;

vec3 texel_direction()
{
    vec2 st = gl_FragCoord.xy * u_params.y * 2.0 - 1.0;
    vec3 fw, sa, ta;
    cube_face_axes(u_face, fw, sa, ta);
    return normalize(fw + st.x * sa + st.y * ta);
}

vec2 hammersley(uint i, uint n)
{
    return vec2(float(i) / float(n), float(bitfieldReverse(i)) * 2.3283064365386963e-10);
}

void tangent_frame(vec3 n, out vec3 t, out vec3 b)
{
    vec3 up = abs(n.y) < 0.999 ? vec3(0, 1, 0) : vec3(1, 0, 0);
    t = normalize(cross(up, n));
    b = cross(n, t);
}
