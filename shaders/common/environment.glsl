// The look's environment: what the sky pass draws behind the scene and what
// the light probes see beyond it (daemon/harness/ibl.c). Chosen by #define
// from look.ibl: ENV_UNIFORM (constant radiance ENV_INTENSITY, the white
// furnace's) or ENV_SKY (the default: an analytic sky made in code, a
// horizon-to-zenith gradient over a darker ground, with a sun disk and its
// glow), scaled by ENV_INTENSITY.
#ifndef ENV_INTENSITY
#define ENV_INTENSITY 1.0
#endif

const vec3 ENV_SUN_DIR = vec3(0.48, 0.62, -0.62); // normalised below
const float ENV_SUN_COS = 0.99863;                 // a disk 3 degrees across
const float ENV_SUN_RADIANCE = 20.0;

vec3 environment_radiance(vec3 d)
{
#if defined(ENV_UNIFORM)
    return vec3(ENV_INTENSITY);
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
