// The look's environment: what the sky pass draws behind the scene and what
// the light probes see beyond it (daemon/harness/ibl.c). Chosen by #define
// from look.ibl: ENV_UNIFORM (constant radiance ENV_INTENSITY, the white
// furnace's), ENV_MAP (an uploaded equirectangular HDR image, bound at
// SB_TEX_ENV_MAP: daemon/scene/environment.h has its mapping) or ENV_SKY
// (the default: an analytic sky made in code, a horizon-to-zenith gradient
// over a darker ground, with a sun disk and its glow), scaled by
// ENV_INTENSITY.
#ifndef ENV_INTENSITY
#define ENV_INTENSITY 1.0
#endif

const vec3 ENV_SUN_DIR = vec3(0.48, 0.62, -0.62); // normalised below
const float ENV_SUN_COS = 0.99863;                 // a disk 3 degrees across
const float ENV_SUN_RADIANCE = 20.0;

#if defined(ENV_MAP)
layout(binding = SB_TEX_ENV_MAP) uniform sampler2D u_env_map;

// The map seen along d, through a pixel of angle pixel_angle (radians): the
// mip level whose texels are about that wide, so that a small capture face
// averages the map rather than aliasing it.
vec3 environment_map(vec3 d, float pixel_angle)
{
    const float PI = 3.14159265358979;
    d = normalize(d);
    vec2 uv = vec2(0.5 + atan(d.z, d.x) / (2.0 * PI), acos(clamp(d.y, -1.0, 1.0)) / PI);
    float texels = pixel_angle * float(textureSize(u_env_map, 0).x) / (2.0 * PI);
    return textureLod(u_env_map, uv, log2(max(texels, 1.0))).rgb * ENV_INTENSITY;
}
#endif

vec3 environment_radiance(vec3 d)
{
#if defined(ENV_UNIFORM)
    return vec3(ENV_INTENSITY);
#elif defined(ENV_MAP)
    return environment_map(d, 0.0);
#else
    d = normalize(d);
    vec3 zenith = vec3(0.18, 0.32, 0.62), horizon = vec3(0.62, 0.70, 0.80);
    vec3 ground = vec3(0.16, 0.14, 0.12);
    vec3 c;
    if (d.y >= 0.0)
        c = mix(horizon, zenith, sqrt(d.y));
    else
        c = mix(horizon * 0.55, ground, sqrt(min(-d.y * 4.0, 1.0)));
    float cs = dot(d, normalize(ENV_SUN_DIR));
    vec3 sun = vec3(1.0, 0.93, 0.82);
    c += sun * (ENV_SUN_RADIANCE * smoothstep(ENV_SUN_COS - 0.0002, ENV_SUN_COS, cs) +
                0.35 * pow(max(cs, 0.0), 48.0));
    return c * ENV_INTENSITY;
#endif
}
