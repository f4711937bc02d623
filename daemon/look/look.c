#define _POSIX_C_SOURCE 200809L
#include "daemon/look/look.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "common/result_keys.h"
#include "common/clock.h"
#include "daemon/lighting/pbr_math.h"
#include "daemon/lighting/shadow_plan.h"

/* A GLSL float literal (always with a point or exponent). */
static void glsl_float(char *out, size_t cap, double v)
{
    snprintf(out, cap, "%.9g", v);
    if (!strpbrk(out, ".eE") && strlen(out) + 2 < cap)
        strcat(out, ".0");
}

void look_defines(const struct look_spec *look, char *out, size_t cap)
{
    static const char *const models[] = {"PHONG", "BLINN_PHONG", "PBR"};
    char rough[32], intensity[32], bias[32], offset[32];
    glsl_float(rough, sizeof(rough), PBR_MIN_ROUGHNESS);
    glsl_float(intensity, sizeof(intensity), look->ibl.intensity);
    int used = snprintf(out, cap,
                        "#define LIGHTING_%s 1\n#define PBR_MIN_ROUGHNESS %s\n#define ENV_%s 1\n"
                        "#define ENV_INTENSITY %s\n",
                        models[look->lighting], rough,
                        look->ibl.environment == IBL_ENV_UNIFORM ? "UNIFORM"
                        : look->ibl.environment == IBL_ENV_ASSET && look->ibl.enabled ? "MAP"
                                                                                      : "SKY",
                        intensity);
    if (look->ibl.enabled && used > 0 && (size_t)used < cap)
        used += snprintf(out + used, cap - (size_t)used,
                         "#define LOOK_IBL 1\n#define IBL_MAX_BLEND %d\n", IBL_MAX_BLEND);
    if (look->debug != LOOK_DEBUG_NONE && used > 0 && (size_t)used < cap) {
        char name[48];
        size_t k = 0;
        for (const char *p = look_debug_names[look->debug]; *p && k + 1 < sizeof(name); p++)
            name[k++] = (char)(*p >= 'a' && *p <= 'z' ? *p - 'a' + 'A' : *p);
        name[k] = '\0';
        used += snprintf(out + used, cap - (size_t)used, "#define LOOK_DEBUG 1\n#define LOOK_DEBUG_%s 1\n",
                         name);
    }
    if (look->shadows.enabled && used > 0 && (size_t)used < cap) {
        const struct shadow_spec *s = &look->shadows;
        glsl_float(bias, sizeof(bias), s->bias);
        glsl_float(offset, sizeof(offset), s->normal_offset);
        snprintf(out + used, cap - (size_t)used,
                 "#define LOOK_SHADOWS 1\n#define SHADOW_PCF %d\n#define SHADOW_BIAS %s\n"
                 "#define SHADOW_NORMAL_OFFSET %s\n#define SHADOW_ATLAS_SIZE %d.0\n%s",
                 s->pcf, bias, offset, s->atlas,
                 s->layout == SHADOW_LAYOUT_CUBES ? "#define SHADOW_CUBES 1\n" : "");
    }
}

bool look_stages_init(struct look_stages *l, const struct look_spec *look,
                       const struct scene *scene, struct gpu_scene *gpu,
                       struct gpu_frame_block *frame_block, const struct gpu_caps *caps,
                       struct gpu_budget *budget, const char *defines,
                       const struct environment_image *env, char *err, size_t errlen)
{
    memset(l, 0, sizeof(*l));
    l->budget = budget;
    l->look = look;
    l->scene = scene;
    l->gpu = gpu;
    double t0 = clock_mono_s();
    l->debug_on = look->debug != LOOK_DEBUG_NONE;
    /* An uploaded environment is drawn behind every scene, as a glTF
     * viewer shows it (not behind a debug channel, which the viewer draws
     * on its clear colour). */
    bool env_map = look->ibl.enabled && look->ibl.environment == IBL_ENV_ASSET;
    if (env_map && !env) {
        snprintf(err, errlen, "look.ibl.environment: the environment \"%s\" was not loaded",
                 look->ibl.env_asset);
        goto fail;
    }
    l->sky_on = (scene->sky || env_map) && !l->debug_on;
    if ((l->sky_on || look->ibl.enabled) &&
        !look_sky_init(&l->sky, defines, env_map ? env : NULL, err, errlen))
        goto fail;
    if (l->debug_on && !look_debug_init(&l->debug, gpu, defines, err, errlen))
        goto fail;
    if (look->ibl.enabled) {
        struct look_ibl_env env = {&look->ibl, scene, gpu, frame_block, &l->sky, budget};
        if (!(l->ibl = look_ibl_create(&env, err, errlen)))
            goto fail;
    }
    if (look->shadows.enabled &&
        !(l->shadows = look_shadows_create(&look->shadows, scene, gpu, caps, err, errlen)))
        goto fail;
    l->setup_ms = (clock_mono_s() - t0) * 1e3;
    return true;
fail:
    look_stages_finish(l);
    return false;
}

void look_stages_finish(struct look_stages *l)
{
    if (!l)
        return;
    look_shadows_destroy(l->shadows);
    look_ibl_destroy(l->ibl);
    look_sky_finish(&l->sky);
    look_debug_finish(&l->debug);
    memset(l, 0, sizeof(*l));
}

bool look_stages_add_passes(const struct look_stages *l, struct gpu_passes *passes,
                             int *shadow_pass, int *sky_pass)
{
    *shadow_pass = *sky_pass = -1;
    if (l->shadows && (*shadow_pass = gpu_passes_add(passes, "shadows")) < 0)
        return false;
    if (l->sky_on && (*sky_pass = gpu_passes_add(passes, "sky")) < 0)
        return false;
    if (l->debug_on && (*sky_pass = gpu_passes_add(passes, "debug")) < 0)
        return false;
    return true;
}

bool look_stages_before(struct look_stages *l, const struct gpu_passes *passes, int shadow_pass,
                         int64_t frame, bool timed, char *err, size_t errlen)
{
    if (l->ibl)
        look_ibl_frame(l->ibl, frame);
    if (l->shadows && shadow_pass >= 0)
        return look_shadows_render(l->shadows, passes, shadow_pass, frame, timed, l->budget, err,
                                   errlen);
    return true;
}

void look_stages_after(struct look_stages *l, const struct gpu_passes *passes, int sky_pass,
                        GLuint output_fbo, int width, int height)
{
    if ((!l->sky_on && !l->debug_on) || sky_pass < 0)
        return;
    gpu_pass_begin(passes, sky_pass, output_fbo, width, height);
    if (l->debug_on)
        look_debug_draw(&l->debug, l->gpu);
    else
        look_sky_draw(&l->sky);
    gpu_pass_end(passes);
}

void look_stages_describe(const struct look_stages *l, json_t *result)
{
    if (l->ibl)
        json_object_set_new(result, "ibl", look_ibl_describe(l->ibl));
    if (l->shadows)
        json_object_set_new(result, RK_SHADOWS, look_shadows_describe(l->shadows));
    if (l->ibl || l->shadows || l->sky_on)
        json_object_set_new(result, "setup_ms",
                            json_pack("{s:f, s:s}", "look", l->setup_ms, "includes",
                                      "the sky, image-based lighting's captures and filtering, "
                                      "and the shadow maps' allocation, before the warm-up "
                                      "frames"));
    if (l->look->lighting == LOOK_PBR) {
        int clamped = 0;
        for (int i = 0; i < l->scene->instance_count; i++)
            clamped += l->scene->instances[i].material.roughness < PBR_MIN_ROUGHNESS;
        json_object_set_new(result, "pbr",
                            json_pack("{s:f, s:i, s:s}", "min_roughness", PBR_MIN_ROUGHNESS,
                                      "materials_clamped", clamped, "rule",
                                      "roughness below min_roughness is shaded at it: GGX at "
                                      "roughness 0 divides 0 by 0 where N = H"));
    }
}
