#include "daemon/jobs/job_eta.h"

#include <math.h>
#include <pthread.h>
#include <string.h>

#include "common/result_keys.h"
#include "daemon/spec/job_spec.h"

/* Frames the harness draws of its own before a run's timed frames
 * (measure.c): the first warm-up frame is measured in slices and the second
 * drawn whole to decide; a job with fewer warm-up frames gets that many
 * more. The measured frame costs more than a whole one: count it twice. */
static double extra_frames(int warmup_frames)
{
    int missing = 2 - warmup_frames;
    return 1.0 + (missing > 0 ? missing : 0);
}

struct sample {
    double pixels, frame_s, overhead_s;
    double fixed_s; /* of frame_s, what no pixel pays for */
    int lights;
};

struct technique_samples {
    char name[32];
    struct sample s[JOB_ETA_SAMPLES];
    int count, next;
};

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static struct technique_samples table[TECHNIQUE_MAX];

static struct technique_samples *find(const char *technique, bool add)
{
    for (int i = 0; i < TECHNIQUE_MAX; i++) {
        if (strcmp(table[i].name, technique) == 0)
            return &table[i];
        if (!table[i].name[0]) {
            if (!add)
                return NULL;
            memset(&table[i], 0, sizeof(table[i]));
            strncpy(table[i].name, technique, sizeof(table[i].name) - 1);
            return &table[i];
        }
    }
    return NULL;
}

void job_eta_observe(const char *technique, double pixels, int lights, double frame_s,
                     double pixel_share, double frames_drawn, double run_s)
{
    if (!technique || pixels <= 0 || !(frame_s > 0) || !(run_s > 0))
        return;
    pthread_mutex_lock(&lock);
    struct technique_samples *t = find(technique, true);
    if (t) {
        double overhead = run_s - frame_s * frames_drawn;
        double share = pixel_share > 0 ? (pixel_share < 1 ? pixel_share : 1) : 0;
        t->s[t->next] = (struct sample){pixels, frame_s, overhead > 0 ? overhead : 0,
                                        frame_s * (1.0 - share), lights};
        t->next = (t->next + 1) % JOB_ETA_SAMPLES;
        if (t->count < JOB_ETA_SAMPLES)
            t->count++;
    }
    pthread_mutex_unlock(&lock);
}

void job_eta_reset(void)
{
    pthread_mutex_lock(&lock);
    memset(table, 0, sizeof(table));
    pthread_mutex_unlock(&lock);
}

static int lights_of(const struct job_spec *spec)
{
    return spec->scene.lights == SCENE_LIGHTS_AUTO ? SCENE_ASSET_DEFAULT_LIGHTS
                                                   : spec->scene.lights;
}

void job_eta_estimate(const struct job_spec *spec, struct job_eta *out)
{
    memset(out, 0, sizeof(*out));
    double pixels = (double)spec->scene.width * spec->scene.height;
    int lights = lights_of(spec);
    pthread_mutex_lock(&lock);
    struct technique_samples *t = find(spec->technique, false);
    /* The nearest in pixels and lights (log scale), the newest of equals. */
    const struct sample *best = NULL;
    double best_d = INFINITY;
    for (int i = 0; t && i < t->count; i++) {
        const struct sample *s = &t->s[(t->next - 1 - i + 2 * JOB_ETA_SAMPLES) % JOB_ETA_SAMPLES];
        double dl = log((lights + 1.0) / (s->lights + 1.0)), dp = log(pixels / s->pixels);
        double d = dl * dl + dp * dp;
        if (d < best_d)
            best = s, best_d = d;
    }
    if (best) {
        out->known = true;
        out->basis_frame_s = best->frame_s;
        out->basis_pixels = best->pixels;
        out->basis_lights = best->lights;
        out->basis_overhead_s = best->overhead_s;
        out->basis_fixed_s = best->fixed_s;
    }
    pthread_mutex_unlock(&lock);
    if (!out->known)
        return;
    /* What no pixel pays for stays; the rest scales with the pixels and
     * the lights. */
    double scale = pixels / out->basis_pixels;
    out->frame_s = out->basis_fixed_s + (out->basis_frame_s - out->basis_fixed_s) * scale *
                                            sqrt((lights + 1.0) / (out->basis_lights + 1.0));
    double frames = (spec->frames + spec->warmup_frames + extra_frames(spec->warmup_frames)) *
                    (double)job_spec_runs(spec);
    /* The reference renders each capture once more (about a frame each). */
    if (spec->reference[0])
        frames += job_spec_capture_count(spec) *
                  (double)spec->reference_supersample * spec->reference_supersample;
    out->duration_s = out->frame_s * frames + out->basis_overhead_s;
}

json_t *job_eta_json(const struct job_eta *e)
{
    if (!e->known)
        return json_null();
    return json_pack("{s:f, s:f, s:{s:f, s:f, s:f, s:f, s:f}, s:s}", "duration_s",
                     e->duration_s, "frame_s", e->frame_s, "basis", "frame_s", e->basis_frame_s,
                     "fixed_s", e->basis_fixed_s, "pixels", e->basis_pixels, "lights",
                     e->basis_lights, "overhead_s", e->basis_overhead_s, "rule",
                     "from the job of this technique nearest in pixels and lights (log scale) "
                     "of the last 32 that ended done on this device: its median frame, of "
                     "which the pixels' share (result.timing.pixel_share: its measuring "
                     "frame's tiled work) scales with the pixels and the square root of the "
                     "lights' ratio and the rest stays, times this job's frames (the harness's "
                     "measuring frames and the reference's included), plus the time that job "
                     "took beyond its frames");
}

bool job_eta_admit(const struct job_spec *spec, const struct job_eta *e, struct job_error *err)
{
    if (!e->known)
        return true;
    double bound = job_spec_max_frame_seconds();
    if (bound > 0 && !spec->accept_sliced_timing && e->frame_s > JOB_ETA_REFUSE_FACTOR * bound)
        return job_error_set(err, "scene.width",
                             "a frame of this job is projected to take %.1f s on this device "
                             "(from a %s job of %.0f pixels and %.0f lights at %.3f s a frame), "
                             "more than %g times the %g s one frame may hold the render thread "
                             "(/v1/info: limits.max_frame_seconds): fewer pixels "
                             "(scene.width, scene.height) or lights (scene.lights), or "
                             "\"accept_sliced_timing\": true",
                             e->frame_s, spec->technique, e->basis_pixels, e->basis_lights,
                             e->basis_frame_s, JOB_ETA_REFUSE_FACTOR, bound);
    if (spec->timeout_s > 0 && e->duration_s > JOB_ETA_REFUSE_FACTOR * spec->timeout_s)
        return job_error_set(err, "timeout_s",
                             "the job is projected to take %.0f s on this device (%.3f s a frame, "
                             "from a %s job of %.0f pixels and %.0f lights), more than %g times "
                             "its timeout_s of %g s: fewer frames, pixels or lights, or a larger "
                             "timeout_s",
                             e->duration_s, e->frame_s, spec->technique, e->basis_pixels,
                             e->basis_lights, JOB_ETA_REFUSE_FACTOR, spec->timeout_s);
    return true;
}

double job_eta_left(int frames_done, int frames_total, double elapsed_s)
{
    if (frames_done <= 0 || elapsed_s <= 0 || frames_total < frames_done)
        return -1.0;
    return elapsed_s / frames_done * (frames_total - frames_done);
}

void job_eta_observe_result(const struct job_spec *spec, const json_t *result, double run_s)
{
    double frame_ms = json_number_value(json_object_get(json_object_get(result, RK_FRAME_MS),
                                                         RK_MEDIAN));
    /* A job timed in slices says nothing of whole frames. */
    if (!(frame_ms > 0) || json_is_true(json_object_get(result, "sliced")))
        return;
    json_t *lights = json_object_get(result, "lights");
    double frames = (spec->frames + spec->warmup_frames + extra_frames(spec->warmup_frames)) *
                    (double)job_spec_runs(spec);
    /* Without the measure's split (older results), all of it scales. */
    json_t *split = json_object_get(json_object_get(result, "timing"), "pixel_share");
    double share = json_is_number(split) ? json_number_value(split) : 1.0;
    job_eta_observe(spec->technique, (double)spec->scene.width * spec->scene.height,
                    json_is_integer(lights) ? (int)json_integer_value(lights) : lights_of(spec),
                    frame_ms / 1e3, share, frames, run_s);
}
