// Irradiance map texel: the cosine-weighted mean radiance around the texel's
// normal (E / pi, so that a Lambertian surface of albedo a reflects a times
// it), from cosine-distributed Hammersley samples of the source's level
// u_params.x, where a texel spans about as much as a sample does.
#include "ibl_filter.glsl"

void main()
{
    vec3 n = texel_direction(), t, b;
    tangent_frame(n, t, b);
    uint count = uint(u_params.z);
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < count; i++) {
        vec2 xi = hammersley(i, count);
        float phi = 6.28318530718 * xi.x, sin_t = sqrt(xi.y), cos_t = sqrt(1.0 - xi.y);
        vec3 l = t * (sin_t * cos(phi)) + b * (sin_t * sin(phi)) + n * cos_t;
        sum += textureLod(u_source, l, u_params.x).rgb;
    }
    out_color = vec4(sum / float(count), 1.0);
}
