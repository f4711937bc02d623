#include "daemon/spec/fidelity_spec.h"

#include <stdio.h>
#include <string.h>

const char *const fidelity_channel_names[] = {
    "lit", "shading_normal", "geometric_normal", "normal_texture", "tangent", "bitangent",
    "base_color", "metallic", "roughness",
    "occlusion", "emissive", "uv0", "uv1", "alpha", NULL};

#define ALL_CHANNELS ((1u << FIDELITY_CHANNELS) - 1)

void fidelity_spec_defaults(struct fidelity_spec *f)
{
    f->enabled = false;
    f->channels = ALL_CHANNELS;
    reference_sampler_defaults(&f->sampler);
}

static bool parse_channels(const json_t *v, unsigned *out, struct job_error *err)
{
    if (json_is_string(v) && strcmp(json_string_value(v), "all") == 0) {
        *out = ALL_CHANNELS;
        return true;
    }
    if (!json_is_array(v) || json_array_size(v) == 0 || json_array_size(v) > FIDELITY_CHANNELS)
        return job_error_set(err, "fidelity.channels", "must be \"all\" or a list of 1 to %d "
                             "channel names", FIDELITY_CHANNELS);
    unsigned bits = 1u << FIDELITY_LIT;
    size_t i;
    json_t *x;
    json_array_foreach(v, i, x) {
        const char *name = json_string_value(x);
        int k = 0;
        while (name && fidelity_channel_names[k] && strcmp(fidelity_channel_names[k], name) != 0)
            k++;
        if (!name || !fidelity_channel_names[k]) {
            char field[64];
            snprintf(field, sizeof(field), "fidelity.channels[%zu]", i);
            return job_error_set(err, field, "must be one of lit, shading_normal, "
                                 "geometric_normal, normal_texture, tangent, bitangent, base_color, metallic, roughness, "
                                 "occlusion, emissive, uv0, uv1, alpha");
        }
        bits |= 1u << k;
    }
    *out = bits;
    return true;
}

bool fidelity_spec_parse(const json_t *v, struct fidelity_spec *f, struct job_error *err)
{
    fidelity_spec_defaults(f);
    if (!v || json_is_null(v) || json_is_false(v))
        return true;
    f->enabled = true;
    if (json_is_true(v))
        return true;
    if (!json_is_object(v))
        return job_error_set(err, "fidelity", "must be true, false, null or an object "
                             "(channels, ibl_sampler)");
    const char *key;
    json_t *x;
    json_object_foreach((json_t *)v, key, x) {
        if (strcmp(key, "channels") == 0) {
            if (!parse_channels(x, &f->channels, err))
                return false;
        } else if (strcmp(key, "ibl_sampler") == 0) {
            char field[64], rule[256];
            if (!reference_sampler_parse(x, &f->sampler, field, sizeof(field), rule,
                                         sizeof(rule)))
                return job_error_set(err, field, "%s", rule);
        } else {
            char field[64];
            snprintf(field, sizeof(field), "fidelity.%.40s", key);
            return job_error_set(err, field, "unknown field (channels, ibl_sampler)");
        }
    }
    return true;
}

json_t *fidelity_spec_to_json(const struct fidelity_spec *f)
{
    if (!f->enabled)
        return json_null();
    json_t *ch = json_array();
    for (int k = 0; ch && k < FIDELITY_CHANNELS; k++)
        if (f->channels & (1u << k))
            json_array_append_new(ch, json_string(fidelity_channel_names[k]));
    return json_pack("{s:s, s:o, s:o}", "renderer", "khronos", "channels", ch, "ibl_sampler",
                     reference_sampler_to_json(&f->sampler));
}

int fidelity_channel_count(const struct fidelity_spec *f)
{
    return __builtin_popcount(f->channels);
}

bool fidelity_spec_check_job(const struct fidelity_spec *f, const struct scene_spec *scene,
                             const struct look_spec *look, const char *reference, int repeat,
                             bool repeat_auto, int temporal_frames, int msaa,
                             struct job_error *err)
{
    if (!f->enabled)
        return true;
    if (!scene->asset[0])
        return job_error_set(err, "fidelity", "needs scene.asset: the Khronos viewer draws the "
                             "uploaded glTF file itself");
    if (reference[0])
        return job_error_set(err, "reference", "must be left out with fidelity: the Khronos "
                             "viewer is the reference");
    if (scene->sun)
        return job_error_set(err, "scene.sun", "must be off with fidelity: the presets' sun "
                             "has no KHR_lights_punctual statement (state a directional light "
                             "in scene.light_rig)");
    if (repeat != 1 || repeat_auto || temporal_frames)
        return job_error_set(err, repeat != 1 || repeat_auto ? "repeat" : "temporal",
                             "must be left out with fidelity (one run, compared once)");
    if (look->lighting != LOOK_PBR)
        return job_error_set(err, "look.lighting", "must be \"pbr\" with fidelity: the Khronos "
                             "viewer draws glTF's metallic-roughness model");
    if (msaa != 1)
        return job_error_set(err, "msaa", "must be 1 with fidelity: the Khronos viewer draws "
                             "one sample a pixel");
    if (look->tonemap == LOOK_TONEMAP_REINHARD)
        return job_error_set(err, "look.tonemap", "reinhard: the Khronos viewer has no such "
                             "curve (none, srgb, aces or pbr_neutral)");
    if (look->post.count)
        return job_error_set(err, "look.post", "must be empty with fidelity: the Khronos "
                             "viewer draws no post effects");
    if (look->shadows.enabled)
        return job_error_set(err, "look.shadows", "must be off with fidelity: the Khronos "
                             "viewer casts no shadows");
    if (look->ibl.enabled && look->ibl.environment == IBL_ENV_SKY)
        return job_error_set(err, "look.ibl.environment", "sky: the Khronos viewer takes an "
                             "image; use \"uniform\" or an uploaded .hdr ({\"asset\": NAME})");
    if (look->ibl.enabled && look->ibl.probes)
        return job_error_set(err, "look.ibl.probes", "must be 0 with fidelity: the Khronos "
                             "viewer lights from the environment alone");
    return true;
}

json_t *fidelity_job_body(const char *asset, const json_t *body, struct job_error *err)
{
    static const char *const keys[] = {"technique", "width", "height", "camera", "lights",
                                       "look", "scene", "channels", "ibl_sampler", "labels",
                                       "timeout_s", NULL};
    if (body && !json_is_object(body)) {
        job_error_set(err, "body", "must be a JSON object (or empty)");
        return NULL;
    }
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)body, key, v) {
        int k = 0;
        while (keys[k] && strcmp(keys[k], key) != 0)
            k++;
        if (!keys[k]) {
            char field[64];
            snprintf(field, sizeof(field), "%.60s", key);
            job_error_set(err, field, "unknown field (technique, width, height, camera, "
                          "lights, look, scene, channels, ibl_sampler, labels, timeout_s)");
            return NULL;
        }
    }
    json_t *scene = json_object_get(body, "scene");
    if (scene && !json_is_object(scene)) {
        job_error_set(err, "scene", "must be an object of scene keys");
        return NULL;
    }
    json_t *look = json_object_get(body, "look");
    if (look && !json_is_object(look)) {
        job_error_set(err, "look", "must be an object");
        return NULL;
    }
    scene = scene ? json_deep_copy(scene) : json_object();
    look = look ? json_deep_copy(look) : json_object();
    if (json_object_get(scene, "asset")) {
        json_decref(scene);
        json_decref(look);
        job_error_set(err, "scene.asset", "is the URL's asset: leave it out");
        return NULL;
    }
    json_object_set_new(scene, "asset", json_string(asset));
    json_t *w = json_object_get(body, "width"), *h = json_object_get(body, "height");
    json_object_set_new(scene, "width", w ? json_incref(w) : json_integer(FIDELITY_DEFAULT_WIDTH));
    json_object_set_new(scene, "height", h ? json_incref(h) : json_integer(FIDELITY_DEFAULT_HEIGHT));
    if (json_object_get(body, "camera"))
        json_object_set(scene, "camera", json_object_get(body, "camera"));
    if (json_object_get(body, "lights"))
        json_object_set(scene, "light_rig", json_object_get(body, "lights"));
    if (!json_object_get(look, "lighting"))
        json_object_set_new(look, "lighting", json_string("pbr"));
    /* The viewer's encoding, so that the lit images compare as they are. */
    if (!json_object_get(look, "transfer"))
        json_object_set_new(look, "transfer", json_string("gamma_2.2"));
    json_t *fid = json_object();
    if (json_object_get(body, "channels"))
        json_object_set(fid, "channels", json_object_get(body, "channels"));
    if (json_object_get(body, "ibl_sampler"))
        json_object_set(fid, "ibl_sampler", json_object_get(body, "ibl_sampler"));
    json_t *tech = json_object_get(body, "technique");
    json_t *job = json_pack("{s:o, s:i, s:i, s:i, s:o, s:o, s:o}", "technique",
                            tech ? json_incref(tech) : json_string("forward"), "frames", 1,
                            "warmup_frames", 0, "capture_interval", 1, "scene", scene, "look",
                            look, "fidelity", fid);
    if (job && json_object_get(body, "labels"))
        json_object_set(job, "labels", json_object_get(body, "labels"));
    if (job && json_object_get(body, "timeout_s"))
        json_object_set(job, "timeout_s", json_object_get(body, "timeout_s"));
    return job;
}
