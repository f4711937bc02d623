#define _POSIX_C_SOURCE 200809L
#include "daemon/harness/runner.h"

#include <epoxy/gl.h>
#include <errno.h>
#include <inttypes.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "config.h"
#include "common/clock.h"
#include "daemon/gpu/egl.h"
#include "common/fsutil.h"
#include "daemon/effects/post_chain.h"
#include "daemon/gpu/bindings.h"
#include "daemon/gpu/caps.h"
#include "daemon/gpu/glutil.h"
#include "daemon/gpu/gpu_scene.h"
#include "daemon/gpu/gpu_timer.h"
#include "daemon/gpu/pass.h"
#include "daemon/gpu/targets.h"
#include "common/log.h"
#include "daemon/harness/interference.h"
#include "daemon/harness/deadline.h"
#include "daemon/harness/telemetry.h"
#include "daemon/harness/look.h"
#include "daemon/harness/metrics_stage.h"
#include "common/png_io.h"
#include "daemon/service.h"
#include "common/stats.h"
#include "daemon/techniques/technique.h"
#include "common/result_keys.h"

struct runner {
    struct queue *queue;
    struct metrics_worker *metrics;
    int device;
    bool gl_debug;
    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t ready_cond;
    int ready; /* 0 starting, 1 up, -1 failed */
    atomic_bool alive;
    char error[512];
    json_t *device_json; /* immutable once ready */
    /* Render-thread state shared by every job: limits, the target pool
     * (re-created only when a size or format changes), the frame block and
     * the resolve program. */
    struct gpu_caps caps;
    struct gpu_targets *targets;
    struct gpu_frame_block frame_block;
    GLuint empty_vao;
    GLuint resolve_progs[3]; /* post hook: by look.tonemap (none, reinhard, aces) */
};

static json_t *stats_json(const double *v, size_t n)
{
    struct stats s;
    stats_compute(v, n, &s);
    return json_pack("{s:I, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:[f, f]}", RK_N,
                     (json_int_t)s.n, RK_MEAN, s.mean, RK_MEDIAN, s.median, RK_STDDEV,
                     s.stddev, RK_MIN, s.min, RK_MAX, s.max, RK_P5, s.p5, RK_P95, s.p95,
                     RK_P99, s.p99, RK_CV, s.cv, RK_MEDIAN_CI95, s.median_lo, s.median_hi);
}

static const char *gl_str(GLenum name)
{
    const char *s = (const char *)glGetString(name);
    return s ? s : "";
}

static json_t *collect_device(struct egl_context *egl, const struct gpu_caps *caps)
{
    json_t *d = json_pack("{s:s, s:s, s:s, s:s, s:s, s:s, s:s, s:s, s:i, s:i}",
                          "egl_platform", egl_context_platform(egl), "egl_device",
                          egl_context_device(egl), "egl_vendor", egl_context_egl_vendor(egl),
                          "egl_version", egl_context_egl_version(egl), "gl_vendor",
                          gl_str(GL_VENDOR), "gl_renderer", gl_str(GL_RENDERER), "gl_version",
                          gl_str(GL_VERSION), "glsl_version", gl_str(GL_SHADING_LANGUAGE_VERSION),
                          "max_texture_size", caps->max_texture_size, "max_renderbuffer_size",
                          caps->max_renderbuffer_size);
    json_object_set_new(d, "caps", gpu_caps_json(caps));
    return d;
}

/* Frames the GPU may run behind the CPU, as a double-buffered swap chain allows. */
#define FRAMES_IN_FLIGHT 2

struct run {
    struct runner *runner;
    struct job *job;
    const struct job_spec *spec;
    const struct technique *tech;
    struct scene scene;
    bool scene_ok;
    struct gpu_scene gpu;
    struct gpu_timer *timer;
    struct gpu_passes passes;
    int resolve_pass;
    /* The look's harness work (probes, shadow maps, sky): owned by the run
     * that measures; the reference borrows it. */
    struct harness_look hlook;
    int shadow_pass, sky_pass; /* -1 when the look has none */
    struct hdr_stats *hdr;     /* per capture, when the look is physically based */
    float *hdr_scratch;
    GLuint ldr_fbo;
    struct technique_env env;
    struct technique_products products;
    char defines[512];
    void *state;
    uint8_t **captures;
    int capture_count;
    json_t *heatmap; /* result.heatmap: captured heat maps, when the technique publishes one */
    double *cpu_ms;
    double *frame_ms;
    GLsync fences[FRAMES_IN_FLIGHT];
    struct interference_sample interference[2]; /* store hook: start and end of the timed region */
    /* Post hook: the look this run renders with (the job's, or its
     * reference_look), its effects, the HDR colour the resolve reads, and
     * the non-finite pixels of each capture. */
    const struct look_spec *look;
    struct post_chain *post;
    GLuint hdr_resolved;
    struct post_nonfinite *nonfinite;
    char err[1024];
};

/* The output every technique draws into (HDR colour and a depth texture
 * later passes may sample) and the 8-bit image the resolve writes, from the
 * runner's pool: allocated once per size and format, not per job. */
static bool setup_targets(struct run *run)
{
    const struct gpu_caps *caps = &run->runner->caps;
    struct gpu_targets *pool = run->runner->targets;
    int w = run->spec->scene.width, h = run->spec->scene.height;
    if (w > caps->max_texture_size || h > caps->max_texture_size ||
        w > caps->max_viewport[0] || h > caps->max_viewport[1]) {
        snprintf(run->err, sizeof(run->err),
                 "scene.width/height %dx%d exceed this device's limits "
                 "(GL_MAX_TEXTURE_SIZE %d, GL_MAX_VIEWPORT_DIMS %dx%d)",
                 w, h, caps->max_texture_size, caps->max_viewport[0], caps->max_viewport[1]);
        return false;
    }
    GLenum hdr_format = run->look->hdr == LOOK_HDR_RGBA16F ? GL_RGBA16F : GL_RGBA32F;
    GLuint color = gpu_targets_texture(pool, "output.hdr", hdr_format, w, h, run->err,
                                       sizeof(run->err));
    GLuint depth = color ? gpu_targets_texture(pool, "output.depth", GL_DEPTH_COMPONENT24, w, h,
                                               run->err, sizeof(run->err))
                         : 0;
    GLuint ldr = depth ? gpu_targets_texture(pool, "output.ldr", GL_RGBA8, w, h, run->err,
                                             sizeof(run->err))
                       : 0;
    if (!ldr)
        return false;
    GLuint out = gpu_targets_fbo(pool, "output", &color, 1, depth, run->err, sizeof(run->err));
    run->ldr_fbo = out ? gpu_targets_fbo(pool, "resolve", &ldr, 1, 0, run->err, sizeof(run->err))
                       : 0;
    if (!run->ldr_fbo)
        return false;
    harness_look_defines(run->look, run->defines, sizeof(run->defines));
    run->env = (struct technique_env){
        .frames = run->spec->frames,
        .warmup_frames = run->spec->warmup_frames,
        .capture_interval = run->spec->capture_interval,
        .look = run->look,
        .scene = &run->scene,
        .gpu = &run->gpu,
        .caps = caps,
        .targets = pool,
        .passes = &run->passes,
        .output_fbo = out,
        .output_color = color,
        .output_depth = depth,
        .width = w,
        .height = h,
        .defines = run->defines,
        .products = &run->products,
    };
    return true;
}

/* The per-frame block for frame k: camera, viewport and counts. A still
 * camera's block is the same every frame, so only a moving one is rebuilt. */
static void frame_data(const struct run *run, int64_t k, struct gpu_frame_data *d)
{
    const struct scene *s = run->env.scene;
    if (d->viewport[0] != 0 && !scene_camera_moves(s)) {
        d->counts[0] = (int32_t)(k & 0x7fffffff);
        return;
    }
    struct scene_camera cam;
    scene_camera_at(s, k, &cam);
    memcpy(d->view, cam.view, sizeof(d->view));
    memcpy(d->proj, cam.proj, sizeof(d->proj));
    memcpy(d->view_proj, cam.view_proj, sizeof(d->view_proj));
    memcpy(d->inv_view, cam.inv_view, sizeof(d->inv_view));
    memcpy(d->inv_proj, cam.inv_proj, sizeof(d->inv_proj));
    mat4_invert(d->view_proj, d->inv_view_proj);
    d->eye[0] = cam.eye[0], d->eye[1] = cam.eye[1], d->eye[2] = cam.eye[2], d->eye[3] = 1.0f;
    d->viewport[0] = (float)run->env.width;
    d->viewport[1] = (float)run->env.height;
    d->viewport[2] = 1.0f / (float)run->env.width;
    d->viewport[3] = 1.0f / (float)run->env.height;
    d->clip[0] = cam.near_z, d->clip[1] = cam.far_z, d->clip[2] = d->clip[3] = 0.0f;
    d->counts[0] = (int32_t)(k & 0x7fffffff);
    d->counts[1] = s->light_count;
    d->counts[2] = s->instance_count;
    d->counts[3] = 0;
}

/* The harness's resolve pass: HDR output to the 8-bit image, timed as a pass
 * of every frame so that every technique pays it alike. */
static void resolve(const struct run *run)
{
    struct runner *r = run->runner;
    gpu_pass_begin(&run->passes, run->resolve_pass, run->ldr_fbo, run->env.width,
                   run->env.height);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glUseProgram(r->resolve_progs[run->look->tonemap]);
    glUniform1f(SB_LOC_EXPOSURE, (float)run->look->exposure); /* post hook */
    glActiveTexture(GL_TEXTURE0 + SB_TEX_HDR);
    glBindTexture(GL_TEXTURE_2D, run->hdr_resolved);
    glBindVertexArray(r->empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    gpu_pass_end(&run->passes);
}

/* Post hook: the chain's effects, once the technique has published the
 * normals (if any) that choose their programs. */
static bool build_post_chain(struct run *run, char *err, size_t errlen)
{
    const struct technique_products *p = &run->products;
    return post_chain_build(run->post, p->normal_tex,
                            p->normal_encoding == TECHNIQUE_NORMAL_OCTAHEDRAL, err, errlen);
}

/* Post hook: the look's effects on the technique's HDR output, each a
 * timed pass, between the technique's render and the resolve. */
static void post_chain_run_frame(struct run *run)
{
    run->hdr_resolved = post_chain_run(run->post);
}

/* Post hook: how many pixels of the colour the resolve read were NaN or
 * infinite, at a captured frame, outside the timed region. */
static bool count_nonfinite(struct run *run, int capture)
{
    return post_chain_count_nonfinite(run->post, run->hdr_resolved, &run->nonfinite[capture],
                                      run->err, sizeof(run->err));
}

/* Post hook: a capture's non-finite pixels, and over the job whether every
 * capture was finite (null without captures): the sweeps' finite criterion. */
static json_int_t nonfinite_pixels(const struct post_nonfinite *n)
{
    return (json_int_t)n->nan_pixels + n->inf_pixels + n->overflow_pixels;
}

static json_t *nonfinite_json(const struct post_nonfinite *n)
{
    return json_pack("{s:I, s:I, s:I, s:I}", "pixels", nonfinite_pixels(n), "nan",
                     (json_int_t)n->nan_pixels, "inf", (json_int_t)n->inf_pixels, "overflow",
                     (json_int_t)n->overflow_pixels);
}

static json_t *nonfinite_summary(const struct run *run)
{
    json_int_t worst = 0, with = 0;
    for (int c = 0; c < run->capture_count; c++) {
        json_int_t px = nonfinite_pixels(&run->nonfinite[c]);
        worst = px > worst ? px : worst;
        with += px > 0;
    }
    return json_pack("{s:i, s:I, s:I, s:o, s:s}", RK_CAPTURES, run->capture_count,
                     "captures_with_nonfinite", with, RK_PIXELS_MAX, worst, RK_FINITE,
                     run->capture_count ? json_boolean(with == 0) : json_null(), "counted",
                     "pixels of the HDR colour the resolve read, at each captured frame, with "
                     "R, G or B NaN, infinite, or (rgba16f) at 65504, where a driver that "
                     "clamps an overflowing write leaves it");
}

/* Builds the technique for a run: its options, passes (its own, the look's
 * shadows and sky, the post chain's, then the harness's resolve) and timer. */
static bool setup_technique(struct run *run, const struct technique *tech, const void *options,
                            int64_t timed_frames)
{
    int post_passes = post_spec_pass_names(&run->look->post, NULL, 0); /* post hook */
    int look_passes = (run->hlook.shadows != NULL) + run->hlook.sky_on;
    run->timer = gpu_timer_create(technique_pass_count(tech) + look_passes + post_passes + 1,
                                  timed_frames);
    if (!run->timer) {
        snprintf(run->err, sizeof(run->err), "cannot create GPU timer queries");
        return false;
    }
    bool fits = gpu_passes_init(&run->passes, run->timer, tech->info->passes,
                                run->runner->caps.debug_groups) &&
                harness_look_add_passes(&run->hlook, &run->passes, &run->shadow_pass,
                                        &run->sky_pass);
    /* Post hook: the chain's passes; its effects are built once the technique exists. */
    const struct post_frame frame = {
        .width = run->env.width,
        .height = run->env.height,
        .hdr_format = run->look->hdr == LOOK_HDR_RGBA16F ? GL_RGBA16F : GL_RGBA32F,
        .color = run->env.output_color,
        .depth = run->env.output_depth,
        .targets = run->env.targets,
    };
    if (fits && !(run->post = post_chain_create(&frame, &run->look->post, &run->passes, run->err,
                                                sizeof(run->err))))
        return false;
    if (!fits || (run->resolve_pass = gpu_passes_add(&run->passes, "resolve")) < 0) {
        snprintf(run->err, sizeof(run->err), "%s declares more passes than the harness times",
                 tech->info->name);
        return false;
    }
    run->env.options = options;
    return true;
}

/* Passes in the order a frame runs them: the shadow pass before the
 * technique's, then the rest as declared. Returns the count. */
static int pass_order(const struct run *run, int *order)
{
    int n = 0;
    if (run->shadow_pass >= 0)
        order[n++] = run->shadow_pass;
    for (int s = 0; s < run->passes.count; s++)
        if (s != run->shadow_pass)
            order[n++] = s;
    return n;
}

static void teardown(struct run *run)
{
    if (run->tech && run->state)
        run->tech->destroy(run->state);
    harness_look_finish(&run->hlook);
    free(run->hdr);
    free(run->hdr_scratch);
    post_chain_destroy(run->post); /* post hook */
    free(run->nonfinite);
    gpu_timer_destroy(run->timer);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    gpu_scene_finish(&run->gpu);
    if (run->scene_ok)
        scene_finish(&run->scene);
    json_decref(run->heatmap);
    for (int i = 0; run->captures && i < run->capture_count; i++)
        free(run->captures[i]);
    free(run->captures);
    free(run->cpu_ms);
    free(run->frame_ms);
    for (int i = 0; i < FRAMES_IN_FLIGHT; i++)
        if (run->fences[i])
            glDeleteSync(run->fences[i]);
    /* Leave no error behind for the next job to trip over. */
    char drop[16];
    gl_error_take("teardown", drop, sizeof(drop));
}

/* Encodes the captures and writes timings.csv and the result. Outside
 * every timed region. */
static json_t *write_outputs(struct run *run, double wall_s, double capture_s)
{
    const struct job_spec *spec = run->spec;
    const struct job *job = run->job;
    int n = spec->frames, w0 = spec->warmup_frames;
    int sections = run->passes.count, order[GPU_MAX_PASSES];
    pass_order(run, order);
    double *gpu = malloc((size_t)n * sizeof(double));
    double *sec = malloc((size_t)n * sizeof(double));
    json_t *captures = json_array(), *result = NULL;
    char path[PATH_MAX + 64]; /* job dir + file name */
    if (!gpu || !sec) {
        snprintf(run->err, sizeof(run->err), "out of memory for statistics");
        goto out;
    }
    for (int i = 0; i < n; i++)
        gpu[i] = gpu_timer_ms(run->timer, w0 + i, -1);

    int c = 0;
    for (int k = 1; k <= n; k++) {
        if (!job_spec_is_capture_frame(spec, k))
            continue;
        char name[64];
        snprintf(name, sizeof(name), "frame-%06d.png", k);
        snprintf(path, sizeof(path), "%s/%s", job->dir, name);
        if (!png_write_gl_rgba(path, run->captures[c], spec->scene.width,
                               spec->scene.height, run->err, sizeof(run->err)))
            goto out;
        free(run->captures[c]);
        run->captures[c] = NULL;
        json_t *entry = json_pack("{s:i, s:s, s:o}", "frame", k, "file", name,
                                  "nonfinite", /* post hook */
                                  nonfinite_json(&run->nonfinite[c]));
        if (run->hdr)
            json_object_set_new(entry, "hdr", hdr_stats_json(&run->hdr[c]));
        json_array_append_new(captures, entry);
        c++;
    }

    /* timings.csv: one row per timed frame. */
    size_t cap = (size_t)n * (80 + 24 * (size_t)sections) + 256, used = 0;
    char *csv = malloc(cap);
    if (!csv) {
        snprintf(run->err, sizeof(run->err), "out of memory for timings.csv");
        goto out;
    }
    used += (size_t)snprintf(csv + used, cap - used, "frame,gpu_ms,cpu_ms,frame_ms");
    for (int o = 0; o < sections; o++)
        used += (size_t)snprintf(csv + used, cap - used, ",gpu_%s_ms",
                                 run->passes.names[order[o]]);
    used += (size_t)snprintf(csv + used, cap - used, "\n");
    for (int i = 0; i < n; i++) {
        used += (size_t)snprintf(csv + used, cap - used, "%d,%.6f,%.6f,%.6f", i + 1, gpu[i],
                                 run->cpu_ms[i], run->frame_ms[i]);
        for (int o = 0; o < sections; o++)
            used += (size_t)snprintf(csv + used, cap - used, ",%.6f",
                                     gpu_timer_ms(run->timer, w0 + i, order[o]));
        used += (size_t)snprintf(csv + used, cap - used, "\n");
    }
    snprintf(path, sizeof(path), "%s/timings.csv", job->dir);
    bool csv_ok = fs_write_atomic(path, csv, used);
    free(csv);
    if (!csv_ok) {
        snprintf(run->err, sizeof(run->err), "cannot write %.900s: %s", path, strerror(errno));
        goto out;
    }

    double timed_wall = wall_s - capture_s;
    result = json_pack(
        "{s:s, s:i, s:i, s:f, s:f, s:f, s:o, s:o, s:o, s:I, s:i, s:i, s:o, s:s, s:s, s:I, s:O}",
        RK_TECHNIQUE, run->tech->info->name, "frames", n, "warmup_frames", w0, RK_WALL_S,
        timed_wall, "wall_s_including_captures", wall_s, RK_FPS,
        timed_wall > 0 ? n / timed_wall : 0.0, RK_GPU_MS, stats_json(gpu, (size_t)n),
        RK_CPU_MS, stats_json(run->cpu_ms, (size_t)n), RK_FRAME_MS,
        stats_json(run->frame_ms, (size_t)n), "triangles_per_frame",
        (json_int_t)scene_triangles(&run->scene), "instances", run->scene.instance_count,
        "lights", run->scene.light_count, RK_CAPTURES, captures, "capture_policy",
        "each captured frame is read back with glReadPixels after its GPU timer "
        "query has ended and its CPU time was taken; the readback time is "
        "subtracted from wall_s (wall_s_including_captures keeps it), and PNG "
        "encoding happens after the last timed frame",
        "timing_method",
        "gpu_ms: GL_TIME_ELAPSED per frame from a ring of 8 queries read back a ring "
        "later; cpu_ms: CLOCK_MONOTONIC around the frame's submission and glFlush; "
        "frame_ms: CLOCK_MONOTONIC between frame starts with at most 2 frames in "
        "flight (fence-bounded, as a swap chain), readback time excluded",
        "timer_query_stalls", (json_int_t)gpu_timer_stalls(run->timer), "device",
        run->runner->device_json);
    captures = NULL;
    /* Every pass, the harness's resolve included, in frame order. */
    json_t *by_section = json_object();
    for (int o = 0; o < sections; o++) {
        for (int i = 0; i < n; i++)
            sec[i] = gpu_timer_ms(run->timer, w0 + i, order[o]);
        json_object_set_new(by_section, run->passes.names[order[o]], stats_json(sec, (size_t)n));
    }
    json_object_set_new(result, "gpu_sections_ms", by_section);
    json_object_set_new(result, "look", look_spec_to_json(&run->spec->look));
    json_object_set_new(result, RK_NONFINITE, nonfinite_summary(run)); /* post hook */
    harness_look_describe(&run->hlook, result);
    json_object_set_new(result, "targets_bytes", json_real(gpu_targets_bytes(run->runner->targets)));
    if (run->heatmap)
        json_object_set(result, RK_HEATMAP, run->heatmap);
    json_object_set_new(result, "scene", scene_describe(&run->scene));
    /* Store hook: what could have disturbed the timed region. */
    json_object_set_new(result, RK_INTERFERENCE,
                        interference_json(&run->interference[0], &run->interference[1]));
    if (run->tech->describe) {
        json_t *d = run->tech->describe(run->state);
        if (d)
            json_object_set_new(result, run->tech->info->name, d); /* result[result.technique] */
    }
    snprintf(path, sizeof(path), "%s/result.json", job->dir);
    if (!fs_write_json_atomic(path, result)) {
        snprintf(run->err, sizeof(run->err), "cannot write %.900s: %s", path, strerror(errno));
        json_decref(result);
        result = NULL;
    }
out:
    json_decref(captures);
    free(gpu);
    free(sec);
    return result;
}

/* Post hook: the reference's output targets and lighting for its look
 * (reference_look may differ in format and lighting), over the run's scene. */
static bool reference_targets(struct run *rr, struct run *run)
{
    if (!setup_targets(rr)) {
        snprintf(run->err, sizeof(run->err), "%.1000s", rr->err);
        return false;
    }
    rr->env.scene = run->env.scene;
    rr->env.gpu = run->env.gpu;
    return true;
}

/* Renders the reference technique at exactly the captured frame indices,
 * after the timed run (its time is in no figure). Each frame gets a fresh
 * technique instance, since frame k is a pure function of k: a stateful
 * technique (OSL) then shows what it would at frame k in a run of its own. */
static bool render_reference(struct run *run, enum job_status *status)
{
    const struct job_spec *spec = run->spec;
    const struct technique *ref = technique_find(spec->reference);
    int w = spec->scene.width, h = spec->scene.height;
    uint8_t *pixels = malloc((size_t)w * (size_t)h * 4);
    /* The reference gets a run of its own over the same scene and targets. */
    struct run rr = {.runner = run->runner, .job = run->job, .spec = spec, .tech = ref,
                     .look = &spec->reference_look, .hlook = run->hlook};
    bool ok = false;
    if (!ref || !pixels || !reference_targets(&rr, run) ||
        !setup_technique(&rr, ref, job_spec_reference_options(spec), 1)) {
        snprintf(run->err, sizeof(run->err), "reference %s: cannot prepare it: %.900s",
                 spec->reference, rr.err);
        goto out;
    }
    for (int k = spec->capture_interval; k <= spec->frames; k += spec->capture_interval) {
        if (atomic_load(&run->job->cancel)) {
            *status = JOB_CANCELLED;
            snprintf(run->err, sizeof(run->err), "cancelled while rendering the reference");
            goto out;
        }
        if (job_timed_out(run->job)) {
            job_timeout_message(run->job, "reference", run->err, sizeof(run->err));
            goto out;
        }
        void *state = NULL;
        char why[900] = "";
        if (!ref->create(&rr.env, &state, why, sizeof(why)) ||
            !build_post_chain(&rr, why, sizeof(why))) { /* post hook */
            snprintf(run->err, sizeof(run->err), "reference %s cannot run: %s", ref->info->name,
                     why);
            ref->destroy(state);
            goto out;
        }
        struct gpu_frame_data fd = {0};
        frame_data(&rr, k, &fd);
        gpu_frame_block_update(&run->runner->frame_block, &fd);
        gpu_timer_begin_frame(rr.timer);
        bool drawn = harness_look_before(&rr.hlook, &rr.passes, rr.shadow_pass, k, false, why,
                                         sizeof(why)) &&
                     ref->render(state, &rr.env, k, why, sizeof(why));
        harness_look_after(&rr.hlook, &rr.passes, rr.sky_pass, rr.env.output_fbo, w, h);
        post_chain_run_frame(&rr);
        resolve(&rr);
        gpu_timer_end_frame(rr.timer);
        if (drawn) {
            glBindFramebuffer(GL_READ_FRAMEBUFFER, rr.ldr_fbo);
            glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, pixels);
        }
        ref->destroy(state);
        if (!drawn || gl_error_take("reference rendering", why, sizeof(why))) {
            snprintf(run->err, sizeof(run->err), "reference %s failed: %s", ref->info->name, why);
            goto out;
        }
        char path[PATH_MAX + 32];
        snprintf(path, sizeof(path), "%s/reference-%06d.png", run->job->dir, k);
        if (!png_write_gl_rgba(path, pixels, w, h, run->err, sizeof(run->err)))
            goto out;
    }
    ok = true;
out:
    gpu_timer_destroy(rr.timer);
    post_chain_destroy(rr.post);
    free(pixels);
    return ok;
}

/* The light-count heat map a technique publishes (products.heat_tex: light
 * evaluations per pixel), read back at captured frame k inside the capture
 * bracket (so outside every timed figure) and written as heatmap-NNNNNN.png
 * on a colour ramp from 0 (black) to the frame's largest count (white),
 * with the frame's mean and max in result.heatmap. */
static bool capture_heatmap(struct run *run, int k)
{
    static const float ramp[6][3] = {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}, {1, 1, 0}, {1, 1, 1}};
    size_t n = (size_t)run->env.width * (size_t)run->env.height;
    uint32_t *count = malloc(n * sizeof(uint32_t));
    uint8_t *rgba = malloc(n * 4);
    bool ok = count && rgba;
    if (ok) {
        glBindTexture(GL_TEXTURE_2D, run->products.heat_tex);
        glGetTexImage(GL_TEXTURE_2D, 0, GL_RED_INTEGER, GL_UNSIGNED_INT, count);
        glBindTexture(GL_TEXTURE_2D, 0);
        double sum = 0;
        uint32_t max = 0;
        for (size_t i = 0; i < n; i++)
            sum += count[i], max = count[i] > max ? count[i] : max;
        for (size_t i = 0; i < n; i++) {
            float t = max ? 5.0f * (float)count[i] / (float)max : 0.0f;
            int seg = t >= 5.0f ? 4 : (int)t;
            float f = t - (float)seg;
            for (int ch = 0; ch < 3; ch++)
                rgba[i * 4 + ch] = (uint8_t)(255.0f * (ramp[seg][ch] + f * (ramp[seg + 1][ch] - ramp[seg][ch])) + 0.5f);
            rgba[i * 4 + 3] = 255;
        }
        char name[64], path[PATH_MAX + 64];
        snprintf(name, sizeof(name), "heatmap-%06d.png", k);
        snprintf(path, sizeof(path), "%s/%s", run->job->dir, name);
        ok = png_write_gl_rgba(path, rgba, run->env.width, run->env.height, run->err, sizeof(run->err));
        if (ok && !run->heatmap)
            run->heatmap = json_pack("{s:s, s:s, s:[]}", "unit", "light evaluations per pixel",
                                     "ramp", "black (0), blue, cyan, green, yellow, white (scale_max)",
                                     RK_CAPTURES);
        if (ok)
            json_array_append_new(json_object_get(run->heatmap, RK_CAPTURES),
                                  json_pack("{s:i, s:s, s:f, s:i, s:i}", "frame", k,
                                            "file", name, "mean", sum / (double)n, "max", (int)max,
                                            "scale_max", (int)max));
    } else {
        snprintf(run->err, sizeof(run->err), "out of memory for the heat map");
    }
    free(count);
    free(rgba);
    return ok;
}

/* One measured run: builds the scene and the technique, renders the warm-up
 * and timed frames (capturing only when asked: the first run), and leaves
 * the figures in run. run_index places it in the job's progress. */
static bool measure(struct runner *r, struct run *run, bool capture, int run_index,
                    double *wall_s, double *capture_s, enum job_status *status)
{
    const struct job_spec *spec = run->spec;
    struct job *job = run->job;
    int w0 = spec->warmup_frames, n = spec->frames;
    run->look = &spec->look; /* post hook */
    run->shadow_pass = run->sky_pass = -1;
    run->scene_ok = scene_init(&run->scene, &spec->scene);
    run->capture_count = capture ? job_spec_capture_count(spec) : 0;
    run->captures = calloc((size_t)run->capture_count + 1, sizeof(*run->captures));
    run->nonfinite = calloc((size_t)run->capture_count + 1, sizeof(*run->nonfinite));
    run->cpu_ms = calloc((size_t)n, sizeof(double));
    run->frame_ms = calloc((size_t)n, sizeof(double));
    if (!run->scene_ok || !run->captures || !run->nonfinite || !run->cpu_ms || !run->frame_ms) {
        snprintf(run->err, sizeof(run->err), "out of memory preparing the job");
        return false;
    }
    if (!gpu_scene_init(&run->gpu, &run->scene, run->err, sizeof(run->err)) ||
        !setup_targets(run) ||
        !harness_look_init(&run->hlook, &spec->look, &run->scene, &run->gpu, &r->frame_block,
                           &r->caps, run->defines, run->err, sizeof(run->err)) ||
        !setup_technique(run, run->tech, job_spec_technique_options(spec), (int64_t)w0 + n))
        return false;
    /* Physically based looks report each capture's HDR figures: non-finite
     * pixels (what the roughness clamp keeps out), mean and peak. */
    if (run->capture_count && spec->look.lighting == LOOK_PBR) {
        run->hdr = calloc((size_t)run->capture_count, sizeof(*run->hdr));
        run->hdr_scratch = malloc((size_t)spec->scene.width * (size_t)spec->scene.height * 4 *
                                  sizeof(float));
        if (!run->hdr || !run->hdr_scratch) {
            snprintf(run->err, sizeof(run->err), "out of memory for HDR statistics");
            return false;
        }
    }
    if (!run->tech->create(&run->env, &run->state, run->err, sizeof(run->err)) ||
        !build_post_chain(run, run->err, sizeof(run->err)) || /* post hook */
        gl_error_take("setup", run->err, sizeof(run->err)))
        return false;

    size_t frame_bytes = (size_t)spec->scene.width * (size_t)spec->scene.height * 4;
    for (int c = 0; c < run->capture_count; c++)
        if (!(run->captures[c] = malloc(frame_bytes))) {
            snprintf(run->err, sizeof(run->err), "out of memory for captures");
            return false;
        }

    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    struct gpu_frame_data fd = {0};
    double wall_start = 0, frame_begin = 0;
    int captured = 0;
    *capture_s = 0;
    for (int seq = 0; seq < w0 + n; seq++) {
        int64_t k = (int64_t)seq - w0 + 1;
        if (atomic_load(&job->cancel)) {
            *status = JOB_CANCELLED;
            snprintf(run->err, sizeof(run->err), "cancelled at frame %" PRId64 " of run %d", k,
                     run_index + 1);
            return false;
        }
        if (job_timed_out(job)) {
            job_timeout_message(job, "rendering", run->err, sizeof(run->err));
            return false;
        }
        if (k == 1) {
            /* Warm-up work still queued must not be billed to the timed frames. */
            glFinish();
            interference_sample(&run->interference[0]); /* store hook, outside the timing */
            wall_start = clock_mono_s();
        }
        /* Bound the frames in flight like a swap chain would; the wait is part
         * of the frame interval, never of the CPU submit time. */
        GLsync *fence = &run->fences[seq % FRAMES_IN_FLIGHT];
        if (*fence) {
            glClientWaitSync(*fence, GL_SYNC_FLUSH_COMMANDS_BIT, UINT64_MAX);
            glDeleteSync(*fence);
            *fence = NULL;
        }
        double t0 = clock_mono_s();
        if (k >= 2)
            run->frame_ms[k - 2] += (t0 - frame_begin) * 1e3;
        frame_begin = t0;
        frame_data(run, k, &fd);
        gpu_frame_block_update(&r->frame_block, &fd);
        gpu_timer_begin_frame(run->timer);
        bool ok = harness_look_before(&run->hlook, &run->passes, run->shadow_pass, k, k >= 1,
                                      run->err, sizeof(run->err)) &&
                  run->tech->render(run->state, &run->env, k, run->err, sizeof(run->err));
        harness_look_after(&run->hlook, &run->passes, run->sky_pass, run->env.output_fbo,
                           run->env.width, run->env.height);
        post_chain_run_frame(run);
        resolve(run);
        gpu_timer_end_frame(run->timer);
        glFlush(); /* where a swap would hand the frame to the GPU */
        double t1 = clock_mono_s();
        *fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
        if (!ok)
            return false;
        if (k >= 1)
            run->cpu_ms[k - 1] = (t1 - t0) * 1e3;
        if (run->capture_count && job_spec_is_capture_frame(spec, (int)k)) {
            double c0 = clock_mono_s();
            glBindFramebuffer(GL_READ_FRAMEBUFFER, run->ldr_fbo);
            glReadPixels(0, 0, spec->scene.width, spec->scene.height, GL_RGBA,
                         GL_UNSIGNED_BYTE, run->captures[captured]);
            if (run->hdr)
                harness_hdr_stats(run->env.output_fbo, spec->scene.width, spec->scene.height,
                                  run->hdr_scratch, &run->hdr[captured]);
            if (!count_nonfinite(run, captured++)) /* post hook, billed to the capture */
                return false;
            if (run->products.heat_tex && !capture_heatmap(run, (int)k))
                return false;
            double c = clock_mono_s() - c0;
            *capture_s += c;
            run->frame_ms[k - 1] -= c * 1e3;
        }
        if ((seq & 15) == 15 && gl_error_take("rendering", run->err, sizeof(run->err)))
            return false;
        queue_progress(r->queue, job, run_index * n + (k > 0 ? (int)k : 0));
        telemetry_frames(1);
    }
    glFinish();
    double wall_end = clock_mono_s();
    interference_sample(&run->interference[1]); /* store hook, outside the timing */
    run->frame_ms[n - 1] += (wall_end - frame_begin) * 1e3;
    *wall_s = wall_end - wall_start;
    gpu_timer_drain(run->timer);
    if (run->tech->verify && !run->tech->verify(run->state, run->err, sizeof(run->err)))
        return false;
    return !gl_error_take("rendering", run->err, sizeof(run->err));
}

/* Median of each series in one run's figures, for the across-run summary. */
static json_t *run_summary(int index, double wall_s, json_t *frame, json_t *gpu, json_t *cpu)
{
    return json_pack("{s:i, s:f, s:o, s:o, s:o}", "run", index, RK_WALL_S, wall_s, RK_FRAME_MS,
                     frame, RK_GPU_MS, gpu, RK_CPU_MS, cpu);
}

static json_t *across_runs(const double *medians, size_t n)
{
    struct stats s;
    stats_compute(medians, n, &s);
    double lo, hi;
    json_t *ci = stats_mean_ci95(medians, n, &lo, &hi) ? json_pack("[f, f]", lo, hi) : json_null();
    return json_pack("{s:f, s:f, s:f, s:f, s:f, s:o}", RK_MEAN, s.mean, RK_MEDIAN, s.median,
                     RK_STDDEV, s.stddev, RK_MIN, s.min, RK_MAX, s.max, RK_CI95, ci);
}

/* Runs 2..N of a repeated job, each with the scene rebuilt; with automatic
 * repeats, stops as soon as the frame-time interval has tightened. Adds
 * result.runs and result.repeat, and rewrites result.json. */
static bool repeat_runs(struct runner *r, struct run *first, json_t *result,
                        enum job_status *status)
{
    const struct job_spec *spec = first->spec;
    int planned = spec->repeat, n = spec->frames, w0 = spec->warmup_frames;
    double *med = calloc((size_t)planned * 3, sizeof(double)); /* frame, gpu, cpu */
    double *gpu = malloc((size_t)n * sizeof(double));
    json_t *runs = json_array();
    static const char *const series[3] = {RK_FRAME_MS, RK_GPU_MS, RK_CPU_MS};
    bool ok = med && gpu;
    if (!ok)
        snprintf(first->err, sizeof(first->err), "out of memory for repeats");
    for (int k = 0; ok && k < 3; k++)
        med[k * planned] = json_real_value(json_object_get(json_object_get(result, series[k]), RK_MEDIAN));
    if (ok)
        json_array_append_new(runs, run_summary(1, json_real_value(json_object_get(result, RK_WALL_S)),
                                                json_deep_copy(json_object_get(result, RK_FRAME_MS)),
                                                json_deep_copy(json_object_get(result, RK_GPU_MS)),
                                                json_deep_copy(json_object_get(result, RK_CPU_MS))));
    if (ok) /* store hook: each run's interference */
        json_object_set_new(json_array_get(runs, 0), RK_INTERFERENCE,
                            json_deep_copy(json_object_get(result, RK_INTERFERENCE)));
    int done = 1;
    while (ok && done < planned && !(spec->repeat_auto && stats_is_stable(med, (size_t)done, 0.025))) {
        struct run extra = {.runner = r, .job = first->job, .spec = spec, .tech = first->tech};
        double wall_s = 0, capture_s = 0;
        ok = measure(r, &extra, false, done, &wall_s, &capture_s, status);
        if (ok) {
            for (int i = 0; i < n; i++)
                gpu[i] = gpu_timer_ms(extra.timer, w0 + i, -1);
            json_t *f = stats_json(extra.frame_ms, (size_t)n), *g = stats_json(gpu, (size_t)n),
                   *c = stats_json(extra.cpu_ms, (size_t)n);
            med[done] = json_real_value(json_object_get(f, RK_MEDIAN));
            med[planned + done] = json_real_value(json_object_get(g, RK_MEDIAN));
            med[2 * planned + done] = json_real_value(json_object_get(c, RK_MEDIAN));
            json_array_append_new(runs, run_summary(done + 1, wall_s, f, g, c));
            json_object_set_new(json_array_get(runs, done), RK_INTERFERENCE, /* store hook */
                                interference_json(&extra.interference[0], &extra.interference[1]));
            done++;
        } else {
            char why[900];
            snprintf(why, sizeof(why), "%.890s", extra.err);
            snprintf(first->err, sizeof(first->err), "run %d: %s", done + 1, why);
        }
        teardown(&extra);
    }
    if (ok) {
        bool stable = stats_is_stable(med, (size_t)done, 0.025);
        json_t *rep = json_pack("{s:i, s:i, s:b, s:b, s:s, s:s}", RK_RUNS, done, "planned", planned,
                                "auto", spec->repeat_auto, RK_STABLE, stable, "rule_series",
                                RK_FRAME_MS, "rule",
                                "stable when the 95% confidence interval (Student's t) of the mean "
                                "of per-run median frame_ms is within 2.5% of it, from 3 runs");
        for (int k = 0; k < 3; k++)
            json_object_set_new(rep, series[k], across_runs(med + k * planned, (size_t)done));
        json_object_set_new(result, RK_REPEAT, rep);
        json_object_set_new(result, RK_RUNS, runs);
        runs = NULL;
        queue_progress(r->queue, first->job, planned * n);
        char path[PATH_MAX + 16];
        snprintf(path, sizeof(path), "%s/result.json", first->job->dir);
        if (!fs_write_json_atomic(path, result)) {
            snprintf(first->err, sizeof(first->err), "cannot write %.900s: %s", path, strerror(errno));
            ok = false;
        }
    }
    json_decref(runs);
    free(med);
    free(gpu);
    return ok;
}

static void run_job(struct runner *r, struct job *job)
{
    struct run run = {.runner = r, .job = job, .spec = &job->spec};
    const struct job_spec *spec = &job->spec;
    enum job_status status = JOB_FAILED;
    json_t *result = NULL;

    LOG(LOG_INFO, "job %s: %s, %d+%d frames at %dx%d, %d run(s)", job->id, spec->technique,
        spec->warmup_frames, spec->frames, spec->scene.width, spec->scene.height,
        job_spec_runs(spec));
    service_status("running job %s (%s, %d frames at %dx%d)", job->id, spec->technique,
                   spec->frames, spec->scene.width, spec->scene.height);
    gl_error_take("previous job", run.err, sizeof(run.err));
    run.err[0] = '\0';
    run.tech = technique_find(spec->technique);
    if (!run.tech) {
        snprintf(run.err, sizeof(run.err), "technique %s is not available", spec->technique);
        goto done;
    }
    double wall_s = 0, capture_s = 0;
    if (!measure(r, &run, true, 0, &wall_s, &capture_s, &status))
        goto done;
    result = write_outputs(&run, wall_s, capture_s);
    /* The first run's technique is done with: free it before more runs or the
     * reference claim the device's memory. */
    run.tech->destroy(run.state);
    run.state = NULL;
    if (result && spec->repeat > 1 && !repeat_runs(r, &run, result, &status)) {
        json_decref(result);
        result = NULL;
    }
    if (result && spec->reference[0]) {
        queue_set_phase(r->queue, job, "reference");
        if (!render_reference(&run, &status)) {
            json_decref(result);
            result = NULL;
        }
    }
    if (result)
        status = JOB_DONE;
done:
    if (status != JOB_DONE)
        LOG(LOG_WARN, "job %s %s: %s", job->id, job_status_name(status), run.err);
    else
        LOG(LOG_INFO, "job %s rendered", job->id);
    teardown(&run);
    service_status("idle; last job %s %s", job->id, job_status_name(status));
    if (status == JOB_DONE && spec->reference[0]) {
        queue_set_phase(r->queue, job, "metrics");
        metrics_worker_submit(r->metrics, job, result);
        return;
    }
    queue_finish(r->queue, job, status, status == JOB_DONE ? NULL : run.err, result);
}

/* What every job shares on the render thread; made once the context is up. */
static bool harness_gl_init(struct runner *r, char *err, size_t errlen)
{
    gl_debug_install();
    gpu_caps_query(&r->caps);
    const struct gl_stage stages[] = {
        {GL_VERTEX_SHADER, {"fullscreen.vert"}},
        {GL_FRAGMENT_SHADER, {"resolve.frag"}},
    };
    /* Post hook: one resolve per tone map, in enum look_tonemap order. */
    static const char *const tonemaps[3] = {"#define TONEMAP_NONE 1\n",
                                            "#define TONEMAP_REINHARD 1\n",
                                            "#define TONEMAP_ACES 1\n"};
    r->targets = gpu_targets_create();
    bool ok = r->targets && gpu_frame_block_init(&r->frame_block);
    for (int i = 0; ok && i < 3; i++)
        ok = (r->resolve_progs[i] = gl_program_build("resolve", stages, 2, tonemaps[i], err,
                                                     errlen)) != 0;
    if (!ok) {
        if (!err[0])
            snprintf(err, errlen, "cannot set up the harness's GL objects");
        return false;
    }
    glGenVertexArrays(1, &r->empty_vao);
    return !gl_error_take("harness setup", err, errlen);
}

static void harness_gl_finish(struct runner *r)
{
    gpu_targets_destroy(r->targets);
    r->targets = NULL;
    gpu_frame_block_finish(&r->frame_block);
    for (int i = 0; i < 3; i++)
        glDeleteProgram(r->resolve_progs[i]);
    glDeleteVertexArrays(1, &r->empty_vao);
}

static void *runner_main(void *arg)
{
    struct runner *r = arg;
    char err[512] = "";
    struct egl_context *egl = egl_context_create(r->device, r->gl_debug, err, sizeof(err));
    pthread_mutex_lock(&r->lock);
    if (egl && !harness_gl_init(r, err, sizeof(err))) {
        egl_context_destroy(egl);
        egl = NULL;
    }
    if (egl) {
        r->device_json = collect_device(egl, &r->caps);
        r->ready = 1;
        atomic_store(&r->alive, true);
    } else {
        snprintf(r->error, sizeof(r->error), "%s", err);
        r->ready = -1;
    }
    pthread_cond_broadcast(&r->ready_cond);
    pthread_mutex_unlock(&r->lock);
    if (!egl)
        return NULL;
    LOG(LOG_INFO, "GL context on %s (%s): %s, %s", egl_context_device(egl),
        egl_context_platform(egl), gl_str(GL_RENDERER), gl_str(GL_VERSION));

    struct job *job;
    /* Store hook: the metrics and files of earlier jobs finish before the next job is timed. */
    while ((metrics_worker_wait_idle(r->metrics), job = queue_next(r->queue))) {
        double busy_from = clock_mono_s();
        run_job(r, job);
        telemetry_render_busy(clock_mono_s() - busy_from);
    }
    atomic_store(&r->alive, false);
    harness_gl_finish(r);
    egl_context_destroy(egl);
    return NULL;
}

struct runner *runner_create(struct queue *q, int device, bool gl_debug,
                             char *err, size_t errlen)
{
    struct runner *r = calloc(1, sizeof(*r));
    if (!r) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    r->queue = q;
    r->metrics = metrics_worker_create(q);
    if (!r->metrics) {
        snprintf(err, errlen, "cannot start the metrics thread");
        free(r);
        return NULL;
    }
    r->device = device;
    r->gl_debug = gl_debug;
    atomic_init(&r->alive, false);
    pthread_mutex_init(&r->lock, NULL);
    pthread_cond_init(&r->ready_cond, NULL);
    if (pthread_create(&r->thread, NULL, runner_main, r) != 0) {
        snprintf(err, errlen, "cannot start the render thread");
        metrics_worker_destroy(r->metrics);
        free(r);
        return NULL;
    }
    pthread_mutex_lock(&r->lock);
    while (r->ready == 0)
        pthread_cond_wait(&r->ready_cond, &r->lock);
    pthread_mutex_unlock(&r->lock);
    if (r->ready < 0) {
        snprintf(err, errlen, "%s", r->error);
        pthread_join(r->thread, NULL);
        metrics_worker_destroy(r->metrics);
        free(r);
        return NULL;
    }
    return r;
}

void runner_destroy(struct runner *r)
{
    if (!r)
        return;
    queue_stop(r->queue);
    pthread_join(r->thread, NULL);
    /* After the render thread: it is the only one that hands work over. */
    metrics_worker_destroy(r->metrics);
    json_decref(r->device_json);
    pthread_cond_destroy(&r->ready_cond);
    pthread_mutex_destroy(&r->lock);
    free(r);
}

bool runner_alive(struct runner *r) { return atomic_load(&r->alive); }

json_t *runner_device_json(struct runner *r) { return json_incref(r->device_json); }
