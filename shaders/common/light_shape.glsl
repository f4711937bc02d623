// Where a light can light, for the lighting library and the binning passes:
// the GPU's copy of daemon/scene/light_shape.c (keep the two in step). A
// point light lights its sphere, a spot light the part of it inside its
// outer cone, a directional light everything. Every bound is conservative:
// a culling pass that left out a light contributing anything would no
// longer sum what forward sums.
#include "scene_data.glsl"

int light_type(int i)
{
    return int(lights[i].direction_type.w);
}

// glTF's angular falloff (KHR_lights_punctual's reference implementation):
// t = clamp((cd - cos_outer) scale, 0, 1), squared; cd is the cosine between
// the spot's axis and the direction from the light to the point. Exactly 0
// at and outside the outer cone.
float light_spot_falloff(int i, vec3 to_point)
{
    vec4 cone = lights[i].cone;
    float cd = dot(lights[i].direction_type.xyz, to_point);
    float t = clamp((cd - cone.x) * cone.z, 0.0, 1.0);
    return t * t;
}

// The smallest sphere holding a spot light's cone (apex, unit axis dir,
// range r, half-angle with cosine c and sine s): for angles up to 45
// degrees the sphere through the apex and the rim circle, centre
// apex + dir r / (2c), radius r / (2c); past 45 the rim circle's own sphere,
// centre apex + dir r c, radius r s. Derived in light_shape.h.
void light_cone_bound(vec3 apex, vec3 dir, float r, float c, float s, out vec3 centre,
                      out float radius)
{
    float along;
    if (c >= s) {
        radius = r / (2.0 * c);
        along = radius;
    } else {
        radius = r * s;
        along = r * c;
    }
    centre = apex + dir * along;
}

// The sphere bounding what light i lights from world position pos: false for
// a directional light, which lights everything.
bool light_bound_sphere(int i, vec3 pos, out vec3 centre, out float radius)
{
    int type = light_type(i);
    radius = lights[i].color_radius.w;
    centre = pos;
    if (type == LIGHT_DIRECTIONAL)
        return false;
    if (type == LIGHT_SPOT)
        light_cone_bound(pos, lights[i].direction_type.xyz, radius, lights[i].cone.x,
                         lights[i].cone.w, centre, radius);
    return true;
}

// Whether the spherical sector (apex, unit dir, range, half-angle cosine c
// and sine s) may touch the sphere (sc, sr): Bart Wronski's "cull that cone"
// (2017). Conservative: behind the apex the side distance it takes is less
// than the true one.
bool light_cone_touches_sphere(vec3 apex, vec3 dir, float range, float c, float s, vec3 sc,
                               float sr)
{
    vec3 v = sc - apex;
    float v1 = dot(v, dir);
    float side = sqrt(max(dot(v, v) - v1 * v1, 0.0));
    float closest = c * side - v1 * s;
    return !(closest > sr || v1 > sr + range || v1 < -sr);
}
