#define _POSIX_C_SOURCE 200809L
#include "daemon/spec/job_cost.h"

#include <stdatomic.h>

#include "daemon/spec/job_spec.h"

/* Bytes a pixel, from result.targets_bytes on llvmpipe (256x256, a fresh
 * context each), rounded up:
 *  - the harness's own: HDR colour (16 in rgba32f, 8 in rgba16f), depth 4
 *    and the 8-bit resolve 4;
 *  - a technique's planes, as its info declares them (planes_bpp: 0 for
 *    unlit, forward and osl, the heat map's 4 for forward_plus and
 *    clustered_forward, the g-buffer and the heat map for the deferred
 *    family, 24 to 48 by their layout, the look and the scene);
 *  - a post effect's: bloom 64, ssao 36, toon 32 in rgba32f; each is taken
 *    at bloom's, halved in rgba16f. */
#define HARNESS_BPP(hdr) ((hdr) + 8.0)
#define POST_EFFECT_BPP(hdr) ((hdr) * 4.0)
/* A captured frame: RGBA8 in memory, and its light-count map (uint32) for
 * the techniques that publish one. */
#define CAPTURE_BPP 8.0
/* Per timed frame: frame, CPU and GPU times, and each pass's GPU time (up
 * to TECHNIQUE_MAX_PASSES and the harness's own). */
#define SERIES_DOUBLES_PER_FRAME 24.0

static _Atomic double memory_limit;

void job_cost_set_memory_limit(double bytes) { atomic_store(&memory_limit, bytes > 0 ? bytes : 0); }

double job_cost_memory_limit(void) { return atomic_load(&memory_limit); }

/* The probes' cube-map arrays (RGBA16F with their mip chains, a third
 * more), the environment's and the capture cube, and its depth. */
static double ibl_bytes(const struct ibl_spec *ibl)
{
    if (!ibl->enabled)
        return 0;
    double face = (double)ibl->resolution * ibl->resolution;
    return (ibl->probes + 2) * 6.0 * face * 8.0 * 4.0 / 3.0 + face * 4.0;
}

/* The atlas edge bounds either layout's depth texels (DEPTH_COMPONENT32F). */
static double shadow_bytes(const struct shadow_spec *s)
{
    return s->enabled ? (double)s->atlas * s->atlas * 4.0 : 0;
}

static double hdr_bytes(const struct look_spec *look)
{
    return look->hdr == LOOK_HDR_RGBA16F ? 8.0 : 16.0;
}

/* With msaa > 1 the technique draws into multisampled colour and depth
 * (and the deferred family into a multisampled g-buffer with an edge
 * stencil of its own) that the harness resolves into the single-sample
 * output: those take hdr + 8 bytes a sample, and the planes scale by the
 * samples too. Samples as asked: a driver that gives more (llvmpipe: 4 for
 * 2) takes more, which no GL-free estimate can know. */
static double look_targets_bpp(const struct job_spec *spec, int technique,
                               const struct look_spec *look, int msaa)
{
    double hdr = hdr_bytes(look);
    double samples = msaa > 1 ? msaa : 1;
    const struct technique_info *info =
        spec->catalog && technique >= 0 ? spec->catalog->infos[technique] : NULL;
    double planes = info && info->planes_bpp
                        ? info->planes_bpp(spec->options[technique].bytes, look,
                                           scene_spec_is_asset(&spec->scene), (int)samples)
                        : 0.0;
    return HARNESS_BPP(hdr) + (msaa > 1 ? (hdr + 8.0) * samples : 0.0) + planes +
           look->post.count * POST_EFFECT_BPP(hdr);
}

void job_cost_estimate(const struct job_spec *spec, struct job_cost *out)
{
    double pixels = (double)spec->scene.width * spec->scene.height;
    int captures = job_spec_capture_count(spec);
    bool reference = spec->reference[0] != '\0';
    *out = (struct job_cost){0};
    out->targets_bytes =
        pixels * look_targets_bpp(spec, spec->technique_index, &spec->look, spec->msaa);
    out->look_bytes = ibl_bytes(&spec->look.ibl) + shadow_bytes(&spec->look.shadows);
    out->captures_bytes = captures * pixels * CAPTURE_BPP;
    if (reference) {
        /* Its planes, should its look need more than the job's, and the
         * frame it reads back; its captures go straight to PNG. */
        double extra =
            look_targets_bpp(spec, spec->reference_index, &spec->reference_look, spec->msaa) -
            look_targets_bpp(spec, spec->technique_index, &spec->look, spec->msaa);
        out->reference_bytes = pixels * ((extra > 0 ? extra : 0) + 4.0) +
                               ibl_bytes(&spec->reference_look.ibl) +
                               shadow_bytes(&spec->reference_look.shadows);
        /* Supersampled, it holds every plane at N x N the pixels (the pool
         * makes them anew at that size) and reads back N x N frames. */
        double n2 = (double)spec->reference_supersample * spec->reference_supersample;
        if (n2 > 1)
            out->reference_bytes +=
                pixels * n2 *
                (look_targets_bpp(spec, spec->reference_index, &spec->reference_look, spec->msaa) +
                 4.0);
        /* temporal.frames: the technique's frames of one capture point are
         * kept while the reference's are drawn, with one of the reference's. */
        if (spec->temporal_frames)
            out->temporal_bytes = pixels * 4.0 * (spec->temporal_frames + 2);
        out->metrics_bytes = metrics_memory_bytes(spec->scene.width, spec->scene.height,
                                                  spec->metrics.flip_ppd);
    }
    out->series_bytes = (double)spec->frames * job_spec_runs(spec) * SERIES_DOUBLES_PER_FRAME *
                        sizeof(double);
    /* The asset's decoded textures and geometry, what its upload's size
     * says nothing of (a 2 KB file can decode to gigabytes). */
    out->asset_bytes = spec->scene.asset_bytes;
    out->memory_bytes = out->targets_bytes + out->look_bytes + out->captures_bytes +
                        out->reference_bytes + out->metrics_bytes + out->series_bytes +
                        out->temporal_bytes + out->asset_bytes;
    out->frames_total = (double)(spec->frames + spec->warmup_frames) * job_spec_runs(spec);
    out->pixel_frames = pixels * out->frames_total;
    /* "auto" (an asset scene's default) is counted at the most it can be. */
    out->pixel_light_evaluations =
        out->pixel_frames * (spec->scene.lights == SCENE_LIGHTS_AUTO ? SCENE_ASSET_DEFAULT_LIGHTS
                                                                     : spec->scene.lights);
    const struct ibl_spec *ibl = &spec->look.ibl;
    out->ibl_samples = ibl->enabled ? (ibl->probes + 1) * 6.0 * ibl->resolution *
                                          ibl->resolution * ibl->samples
                                    : 0;
    out->shadow_texels = shadow_bytes(&spec->look.shadows) / 4.0 * out->frames_total;
    out->metric_pixels = reference ? captures * pixels : 0;
    /* The field to change, by the largest part. */
    struct {
        double bytes;
        const char *field;
    } parts[] = {
        {out->targets_bytes, "scene.width"},
        {spec->look.ibl.enabled ? ibl_bytes(&spec->look.ibl) : 0, "look.ibl.resolution"},
        {shadow_bytes(&spec->look.shadows), "look.shadows.atlas"},
        {out->captures_bytes, "capture_interval"},
        {out->reference_bytes + out->metrics_bytes,
         spec->reference_supersample > 1 ? "reference.supersample" : "reference"},
        {out->temporal_bytes, "temporal.frames"},
        {out->series_bytes, "frames"},
        {out->asset_bytes, "scene.asset"},
    };
    out->memory_field = parts[0].field;
    double most = parts[0].bytes;
    for (size_t i = 1; i < sizeof(parts) / sizeof(parts[0]); i++)
        if (parts[i].bytes > most) {
            most = parts[i].bytes;
            out->memory_field = parts[i].field;
        }
}

json_t *job_cost_json(const struct job_cost *c)
{
    json_t *o = json_pack("{s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:{s:f, s:f, s:f, s:f, s:f, s:f}}",
                          "memory_bytes", c->memory_bytes, "targets_bytes", c->targets_bytes,
                          "look_bytes", c->look_bytes, "captures_bytes", c->captures_bytes,
                          "reference_bytes", c->reference_bytes, "metrics_bytes",
                          c->metrics_bytes, "series_bytes", c->series_bytes, "work", "frames",
                          c->frames_total, "pixel_frames", c->pixel_frames,
                          "pixel_light_evaluations", c->pixel_light_evaluations, "ibl_samples",
                          c->ibl_samples, "shadow_texels", c->shadow_texels, "metric_pixels",
                          c->metric_pixels);
    if (c->temporal_bytes > 0)
        json_object_set_new(o, "temporal_bytes", json_real(c->temporal_bytes));
    if (c->asset_bytes > 0)
        json_object_set_new(o, "asset_bytes", json_real(c->asset_bytes));
    return o;
}

bool job_cost_admit(const struct job_cost *c, struct job_error *err)
{
    double limit = job_cost_memory_limit();
    if (limit <= 0 || c->memory_bytes <= limit)
        return true;
    return job_error_set(err, c->memory_field,
                         "the job would take about %.0f MiB (framebuffers %.0f, captures %.0f, "
                         "shadows and probes %.0f, reference and metrics %.0f, the asset's "
                         "textures and geometry %.0f), more than the %.0f MiB a job may take "
                         "(/v1/info: memory.job_bytes)",
                         c->memory_bytes / 1048576.0, c->targets_bytes / 1048576.0,
                         c->captures_bytes / 1048576.0, c->look_bytes / 1048576.0,
                         (c->reference_bytes + c->metrics_bytes) / 1048576.0,
                         c->asset_bytes / 1048576.0, limit / 1048576.0);
}
