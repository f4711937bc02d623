#define _POSIX_C_SOURCE 200809L
#include "daemon/harness/run.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/gpu/bindings.h"
#include "daemon/gpu/glutil.h"
#include "common/clock.h"
#include "daemon/jobs/deadline.h"
#include "daemon/status/render_state.h"
#include "daemon/store/store.h"
#include "daemon/scene/asset.h"

bool harness_gl_init(struct harness_gl *g, char *err, size_t errlen)
{
    gl_debug_install();
    gpu_caps_query(&g->caps);
    gpu_timer_prime();
    const struct gl_stage stages[] = {
        {GL_VERTEX_SHADER, {"fullscreen.vert"}},
        {GL_FRAGMENT_SHADER, {"resolve.frag"}},
    };
    /* One resolve per tone map, in enum look_tonemap order. */
    static const char *const tonemaps[LOOK_TONEMAP_COUNT] = {
        "#define TONEMAP_NONE 1\n", "#define TONEMAP_REINHARD 1\n", "#define TONEMAP_ACES 1\n",
        "#define TONEMAP_SRGB 1\n", "#define TONEMAP_PBR_NEUTRAL 1\n"};
    g->targets = gpu_targets_create();
    bool ok = g->targets && gpu_frame_block_init(&g->frame_block);
    for (int i = 0; ok && i < LOOK_TONEMAP_COUNT; i++)
        ok = (g->resolve_progs[i] = gl_program_build("resolve", stages, 2, tonemaps[i], err,
                                                     errlen)) != 0;
    if (!ok) {
        if (!err[0])
            snprintf(err, errlen, "cannot set up the harness's GL objects");
        return false;
    }
    glGenVertexArrays(1, &g->empty_vao);
    return !gl_error_take("harness setup", err, errlen);
}

void harness_gl_finish(struct harness_gl *g)
{
    gpu_targets_destroy(g->targets);
    g->targets = NULL;
    gpu_frame_block_finish(&g->frame_block);
    for (int i = 0; i < LOOK_TONEMAP_COUNT; i++)
        glDeleteProgram(g->resolve_progs[i]);
    glDeleteVertexArrays(1, &g->empty_vao);
}

/* The output every technique draws into (HDR colour and a depth texture
 * later passes may sample) and the 8-bit image the resolve writes, from the
 * pool: allocated once per size and format, not per job. */
bool run_setup_targets(struct harness_run *run)
{
    const struct gpu_caps *caps = &run->gl->caps;
    struct gpu_targets *pool = run->gl->targets;
    int scale = run->scale > 1 ? run->scale : 1;
    int w = run->spec->scene.width * scale, h = run->spec->scene.height * scale;
    if (w > caps->max_texture_size || h > caps->max_texture_size ||
        w > caps->max_viewport[0] || h > caps->max_viewport[1]) {
        snprintf(run->err, sizeof(run->err),
                 "%s %dx%d exceed this device's limits "
                 "(GL_MAX_TEXTURE_SIZE %d, GL_MAX_VIEWPORT_DIMS %dx%d)",
                 scale > 1 ? "scene.width/height times reference.supersample"
                           : "scene.width/height",
                 w, h, caps->max_texture_size, caps->max_viewport[0], caps->max_viewport[1]);
        return false;
    }
    GLenum hdr_format = run->look->hdr == LOOK_HDR_RGBA16F ? GL_RGBA16F : GL_RGBA32F;
    GLuint color = gpu_targets_texture(pool, "output.hdr", hdr_format, w, h, run->err,
                                       sizeof(run->err));
    GLuint depth = color ? gpu_targets_texture(pool, "output.depth", GL_DEPTH24_STENCIL8, w, h,
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
    run->hdr_fbo = out, run->hdr_color = color, run->hdr_depth = depth;
    run->msaa_pass = -1;
    int samples = run->spec->msaa > 1 ? run->spec->msaa : 1;
    if (samples > 1 && !run_msaa_targets(run, hdr_format, w, h, &samples, &out, &color, &depth))
        return false;
    look_defines(run->look, run->defines, sizeof(run->defines));
    if (scene_spec_is_asset(&run->spec->scene)) {
        /* Every program that draws the scene reads the asset's materials
         * (shaders/common/surface.glsl); the procedural scenes' programs
         * are the same text as ever without it. */
        size_t used = strlen(run->defines);
        snprintf(run->defines + used, sizeof(run->defines) - used, "#define SCENE_TEXTURED 1\n");
    }
    if (samples > 1) {
        /* Programs that sample the output's depth or a g-buffer read every
         * sample: sampler2DMS variants (shaders/common/msaa.glsl). */
        size_t used = strlen(run->defines);
        snprintf(run->defines + used, sizeof(run->defines) - used,
                 "#define SB_MSAA_SAMPLES %d\n", samples);
    }
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
        .samples = samples,
        .defines = run->defines,
        .products = &run->products,
        .budget = &run->budget,
    };
    return true;
}

bool run_build_post_chain(struct harness_run *run)
{
    const struct technique_products *p = &run->products;
    return post_chain_build(run->post, p->normal_tex,
                            p->normal_encoding == TECHNIQUE_NORMAL_OCTAHEDRAL, run->err,
                            sizeof(run->err));
}

bool run_setup_passes(struct harness_run *run, const void *options, int64_t timed_frames)
{
    const struct technique *tech = run->tech;
    int post_passes = post_spec_pass_names(&run->look->post, NULL, 0);
    int look_passes = (run->stages.shadows != NULL &&
                       !(tech->info->flags & TECHNIQUE_READS_NO_LIGHT)) +
                      run->stages.sky_on + run->stages.debug_on +
                      (run->transparent.count > 0);
    /* What the technique and the chain need of time. */
    run->needs = (struct frame_needs){0};
    if (tech->info->needs)
        tech->info->needs(options, &run->needs);
    post_spec_needs(&run->look->post, &run->needs);
    run->motion_pass = -1;
    run->timer = gpu_timer_create(technique_pass_count(tech) + look_passes + post_passes + 1 +
                                      (run->env.samples > 1) + run->needs.motion_vectors,
                                  timed_frames);
    if (!run->timer) {
        snprintf(run->err, sizeof(run->err), "cannot create GPU timer queries");
        return false;
    }
    /* A technique that reads no light draws no shadow pass: the maps, if a
     * reference needs them, are drawn in the reference's frames. */
    struct look_shadows *shadows = run->stages.shadows;
    if (tech->info->flags & TECHNIQUE_READS_NO_LIGHT)
        run->stages.shadows = NULL;
    bool fits = gpu_passes_init(&run->passes, run->timer, tech->info->passes,
                                run->gl->caps.debug_groups) &&
                look_stages_add_passes(&run->stages, &run->passes, &run->shadow_pass,
                                       &run->sky_pass);
    run->stages.shadows = shadows;
    run->transparent_pass = -1;
    if (fits && run->transparent.count > 0 &&
        (run->transparent_pass = gpu_passes_add(&run->passes, "transparent")) < 0)
        fits = false;
    if (fits && run->env.samples > 1 &&
        (run->msaa_pass = gpu_passes_add(&run->passes, "msaa_resolve")) < 0)
        fits = false;
    if (fits && run->needs.motion_vectors) {
        if ((run->motion_pass = gpu_passes_add(&run->passes, "motion_vectors")) < 0)
            fits = false;
        else if (!motion_vectors_init(&run->motion, run->env.targets, run->env.gpu,
                                      run->hdr_depth, run->env.width, run->env.height,
                                      run->defines, run->err, sizeof(run->err)))
            return false;
    }
    /* The chain's passes now; its effects are built once the technique exists. */
    const struct post_frame frame = {
        .width = run->env.width,
        .height = run->env.height,
        .hdr_format = run->look->hdr == LOOK_HDR_RGBA16F ? GL_RGBA16F : GL_RGBA32F,
        .color = run->hdr_color,
        .depth = run->hdr_depth,
        .targets = run->env.targets,
        .budget = &run->budget,
        .motion = run->motion.tex,
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

static bool alloc_captures(struct harness_run *run)
{
    const struct job_spec *spec = run->spec;
    size_t pixels = (size_t)spec->scene.width * (size_t)spec->scene.height;
    int n = run->capture_count;
    if (!n)
        return true;
    if (!(run->capture = calloc((size_t)n, sizeof(*run->capture))))
        return false;
    for (int c = 0; c < n; c++) {
        struct run_capture *cap = &run->capture[c];
        if (!(cap->pixels = malloc(pixels * 4)) ||
            (run->products.heat_tex && !(cap->heat = malloc(pixels * sizeof(uint32_t)))))
            return false;
    }
    /* Physically based looks report each capture's HDR figures: non-finite
     * pixels (what the roughness clamp keeps out), mean and peak. */
    if (run->look->lighting == LOOK_PBR &&
        !(run->hdr_scratch = malloc(pixels * 4 * sizeof(float))))
        return false;
    if (run->motion_pass >= 0 && !(run->motion_scratch = malloc(pixels * 2 * sizeof(float))))
        return false;
    return true;
}

static bool job_stop_requested(void *ctx)
{
    const struct job *job = ctx;
    return atomic_load(&job->cancel) || job_timed_out(job);
}

void run_budget_init(struct harness_run *run)
{
    gpu_budget_init(&run->budget, job_stop_requested, run->job);
    run->budget.progress = render_progress;
}

/* scene.asset: STATE/assets/SHA256.sbasset, the cache the upload wrote,
 * read whole before anything is timed. */
static bool load_asset(struct harness_run *run)
{
    const struct scene_spec *sc = &run->spec->scene;
    if (!sc->asset[0])
        return true;
    if (!sc->asset_sha256[0]) {
        snprintf(run->err, sizeof(run->err),
                 "scene.asset \"%s\": the job carries no asset_sha256 (filled in when the job is "
                 "accepted)", sc->asset);
        return false;
    }
    const char *state = store_state_dir(queue_store(run->queue));
    char path[4096], why[600];
    snprintf(path, sizeof(path), "%s/assets/%s.sbasset", state[0] ? state : ".", sc->asset_sha256);
    struct asset_limits lim;
    asset_limits_defaults(&lim);
    if (!(run->asset = calloc(1, sizeof(*run->asset)))) {
        snprintf(run->err, sizeof(run->err), "out of memory for the asset");
        return false;
    }
    if (!asset_file_read(run->asset, path, &lim, why, sizeof(why))) {
        snprintf(run->err, sizeof(run->err), "scene.asset \"%s\": %s", sc->asset, why);
        return false;
    }
    return true;
}

/* look.ibl.environment {"asset": NAME}: its cache, read whole likewise. */
static bool load_environment(struct harness_run *run)
{
    const struct ibl_spec *ibl = &run->spec->look.ibl;
    if (!ibl->enabled || ibl->environment != IBL_ENV_ASSET)
        return true;
    if (!ibl->env_sha256[0]) {
        snprintf(run->err, sizeof(run->err),
                 "look.ibl.environment \"%s\": the job carries no asset_sha256 (filled in "
                 "when the job is accepted)", ibl->env_asset);
        return false;
    }
    const char *state = store_state_dir(queue_store(run->queue));
    char path[4096], why[600];
    snprintf(path, sizeof(path), "%s/assets/%s.sbasset", state[0] ? state : ".",
             ibl->env_sha256);
    struct environment_limits lim;
    environment_limits_defaults(&lim);
    if (!environment_file_read(&run->environment, path, &lim, why, sizeof(why))) {
        snprintf(run->err, sizeof(run->err), "look.ibl.environment \"%s\": %s",
                 ibl->env_asset, why);
        return false;
    }
    return true;
}

bool run_prepare(struct harness_run *run, bool capture)
{
    const struct job_spec *spec = run->spec;
    int n = spec->frames;
    run->look = &spec->look;
    if ((run->tech->info->flags & TECHNIQUE_READS_NO_LIGHT) && !spec->reference[0]) {
        /* The cost floor pays only for what it draws: no shadow maps, no
         * probes it would never read (with a reference, they are made for
         * the reference, which draws them in its own frames). */
        run->look_unlit = spec->look;
        run->look_unlit.shadows.enabled = false;
        run->look_unlit.ibl.enabled = false;
        run->look = &run->look_unlit;
    }
    run->shadow_pass = run->sky_pass = run->transparent_pass = -1;
    run_budget_init(run);
    double t0 = clock_mono_s();
    if (!load_asset(run) || !load_environment(run))
        return false;
    double t1 = clock_mono_s();
    char why[600];
    run->scene_ok = scene_build(&run->scene, &spec->scene, run->asset, why, sizeof(why));
    if (!run->scene_ok) {
        snprintf(run->err, sizeof(run->err), "%s", why);
        return false;
    }
    run->capture_count = capture ? job_spec_capture_count(spec) : 0;
    run->cpu_ms = calloc((size_t)n, sizeof(double));
    run->frame_ms = calloc((size_t)n, sizeof(double));
    run->drawn_whole = calloc((size_t)n, 1);
    if (!run->cpu_ms || !run->frame_ms || !run->drawn_whole) {
        snprintf(run->err, sizeof(run->err), "out of memory preparing the job");
        return false;
    }
    gpu_targets_new_epoch(run->gl->targets);
    if (!gpu_scene_init(&run->gpu, &run->scene, run->err, sizeof(run->err)))
        return false;
    if (run->asset) {
        glFinish();
        run->asset_read_ms = (t1 - t0) * 1e3;
        run->scene_upload_ms = (clock_mono_s() - t1) * 1e3;
    }
    if (!run_setup_targets(run) ||
        !look_stages_init(&run->stages, run->look, &run->scene, &run->gpu,
                          &run->gl->frame_block, &run->gl->caps, &run->budget, run->defines,
                          run->environment.rgb ? &run->environment : NULL, run->err,
                          sizeof(run->err)) ||
        !transparent_init(&run->transparent, &run->gpu, run->defines, run->err,
                          sizeof(run->err)) ||
        !run_setup_passes(run, job_spec_technique_options(spec),
                          (int64_t)spec->warmup_frames + n))
        return false;
    if (!run->tech->create(&run->env, &run->state, run->err, sizeof(run->err)) ||
        !run_build_post_chain(run) ||
        gl_error_take("setup", run->err, sizeof(run->err)))
        return false;
    /* After create: whether the technique publishes a heat map is known now. */
    if (!alloc_captures(run)) {
        snprintf(run->err, sizeof(run->err), "out of memory for captures");
        return false;
    }
    return true;
}

bool run_recreate_technique(struct harness_run *run)
{
    run->tech->destroy(run->state);
    run->state = NULL;
    /* Its planes come from the target pool by name: the post chain's and
     * the captures' views of them stay valid. */
    memset(&run->products, 0, sizeof(run->products));
    return run->tech->create(&run->env, &run->state, run->err, sizeof(run->err));
}

void run_finish(struct harness_run *run)
{
    if (run->tech && run->state)
        run->tech->destroy(run->state);
    run->state = NULL;
    look_stages_finish(&run->stages);
    transparent_finish(&run->transparent);
    motion_vectors_finish(&run->motion);
    gl_build_log_free(&run->builds);
    free(run->hdr_scratch);
    free(run->motion_scratch);
    post_chain_destroy(run->post);
    gpu_timer_destroy(run->timer);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    gpu_scene_finish(&run->gpu);
    if (run->scene_ok)
        scene_finish(&run->scene);
    if (run->asset) {
        asset_finish(run->asset);
        free(run->asset);
        run->asset = NULL;
    }
    environment_image_finish(&run->environment);
    for (int i = 0; run->capture && i < run->capture_count; i++) {
        free(run->capture[i].pixels);
        free(run->capture[i].heat);
    }
    free(run->capture);
    free(run->cpu_ms);
    free(run->frame_ms);
    free(run->drawn_whole);
    for (int i = 0; i < RUN_FRAMES_IN_FLIGHT; i++)
        if (run->fences[i])
            glDeleteSync(run->fences[i]);
    /* Leave no error behind for the next job to trip over. */
    char drop[16];
    gl_error_take("teardown", drop, sizeof(drop));
}

/* m (a projection, or a view-projection) followed by the jitter: every
 * clip-space x and y moves by its offset times w (an orthographic
 * projection's too), so that the image moves by jitter pixels. The jitter
 * is a translation applied after m, so a view-projection takes it the same
 * way as the projection. */
static void jitter_matrix(float m[16], const float jitter[2], int w, int h)
{
    float dx = 2.0f * jitter[0] / (float)w, dy = 2.0f * jitter[1] / (float)h;
    for (int c = 0; c < 4; c++) {
        m[c * 4 + 0] += dx * m[c * 4 + 3];
        m[c * 4 + 1] += dy * m[c * 4 + 3];
    }
}

/* A still, unjittered camera's block is the same every frame, so only a
 * moving or jittered one is rebuilt. */
void run_frame_data(const struct harness_run *run, int64_t k, const float jitter[2],
                    const float prev_jitter[2], struct gpu_frame_data *d)
{
    const struct scene *s = run->env.scene;
    bool jittered = jitter[0] != 0.0f || jitter[1] != 0.0f;
    bool moves = scene_camera_moves(s);
    if (d->viewport[0] != 0 && !moves && !jittered && d->jitter[0] == 0.0f &&
        d->jitter[1] == 0.0f) {
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
    memcpy(d->unjittered_view_proj, cam.view_proj, sizeof(d->unjittered_view_proj));
    if (jittered) {
        jitter_matrix(d->proj, jitter, run->env.width, run->env.height);
        jitter_matrix(d->view_proj, jitter, run->env.width, run->env.height);
        mat4_invert(d->proj, d->inv_proj);
    }
    mat4_invert(d->view_proj, d->inv_view_proj);
    if (moves) {
        struct scene_camera before;
        scene_camera_at(s, k - 1, &before);
        memcpy(d->prev_view_proj, before.view_proj, sizeof(d->prev_view_proj));
    } else {
        memcpy(d->prev_view_proj, cam.view_proj, sizeof(d->prev_view_proj));
    }
    d->jitter[0] = jitter[0], d->jitter[1] = jitter[1];
    d->jitter[2] = prev_jitter[0], d->jitter[3] = prev_jitter[1];
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

bool run_history_restarts(const struct harness_run *run, int64_t k)
{
    int h = run->needs.history_frames;
    return !run->drawn || k != run->last_frame + 1 ||
           (h > 0 && technique_env_captures(&run->env, k + h));
}

/* HDR output to the 8-bit image, timed as a pass of every frame so that
 * every technique pays it alike. */
static void resolve(const struct harness_run *run)
{
    const struct harness_gl *g = run->gl;
    gpu_pass_begin(&run->passes, run->resolve_pass, run->ldr_fbo, run->env.width,
                   run->env.height);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    /* look.debug's channels are written as they are: no exposure, no curve. */
    bool raw = run->look->debug != LOOK_DEBUG_NONE;
    glUseProgram(g->resolve_progs[raw ? LOOK_TONEMAP_NONE : run->look->tonemap]);
    glUniform1f(SB_LOC_EXPOSURE, raw ? 1.0f : (float)run->look->exposure);
    glUniform1f(SB_LOC_GAMMA,
                !raw && run->look->transfer == LOOK_TRANSFER_GAMMA_2_2 ? 2.2f : 0.0f);
    glActiveTexture(GL_TEXTURE0 + SB_TEX_HDR);
    glBindTexture(GL_TEXTURE_2D, run->hdr_resolved);
    glBindVertexArray(g->empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    gpu_pass_end(&run->passes);
}

bool run_frame(struct harness_run *run, int64_t k, bool timed)
{
    gpu_budget_frame(&run->budget);
    /* Time: the frame, whether histories restart at it, the jitter. */
    struct gpu_frame_time *t = &run->time;
    float prev_jitter[2];
    frame_jitter(run->needs.jitter_length, k - 1, prev_jitter);
    t->frame = k;
    t->restart = run_history_restarts(run, k);
    frame_jitter(run->needs.jitter_length, k, t->jitter);
    run->env.time = t;
    run_frame_data(run, k, t->jitter, prev_jitter, &run->frame_data);
    gpu_frame_block_update(&run->gl->frame_block, &run->frame_data);
    gpu_scene_set_frame(run->env.gpu, k);
    run->drawn = true;
    run->last_frame = k;
    gpu_timer_begin_frame(run->timer);
    bool ok = look_stages_before(&run->stages, &run->passes, run->shadow_pass, k, timed, run->err,
                                 sizeof(run->err));
    /* The technique's first pass is timed from here: work it submits before
     * its first gpu_pass_begin (OSL's lighting dispatch) counts to it, not
     * to the look's shadow pass before it. */
    gpu_timer_section(run->timer, 0);
    ok = ok && run->tech->render(run->state, &run->env, k, run->err, sizeof(run->err));
    if (!ok && gpu_budget_stopped(&run->budget)) {
        /* Abandoned where it was told to stop: nothing more is drawn. */
        gpu_timer_end_frame(run->timer);
        return false;
    }
    look_stages_after(&run->stages, &run->passes, run->sky_pass, run->env.output_fbo,
                      run->env.width, run->env.height);
    if (run->transparent_pass >= 0)
        transparent_draw(&run->transparent, run->env.gpu, &run->passes, run->transparent_pass,
                         run->env.output_fbo, run->env.width, run->env.height,
                         run->frame_data.eye);
    if (run->msaa_pass >= 0)
        run_msaa_resolve(run);
    if (run->motion_pass >= 0)
        motion_vectors_draw(&run->motion, &run->passes, run->motion_pass, run->env.gpu);
    if (ok)
        ok = post_chain_run(run->post, t, &run->hdr_resolved, run->err, sizeof(run->err));
    if (ok)
        resolve(run);
    gpu_timer_end_frame(run->timer);
    return ok;
}

static json_t *needs_json(const struct frame_needs *n)
{
    return json_pack("{s:i, s:o, s:b}", "history_frames", n->history_frames, "jitter",
                     n->jitter_length
                         ? json_pack("{s:s, s:i}", "sequence",
                                     "Halton (2, 3) from index 1, centred on the pixel", "length",
                                     n->jitter_length)
                         : json_null(),
                     "motion_vectors", n->motion_vectors);
}

json_t *run_time_json(const struct harness_run *run)
{
    const struct job_spec *spec = run->spec;
    struct frame_needs ref = {0};
    int dropped = 0;
    if (spec->reference[0]) {
        job_spec_needs(spec, true, &ref);
        struct post_spec all = spec->look.post;
        dropped = spec->reference_look_given ? 0 : post_spec_drop_antialiasing(&all);
    }
    const struct frame_needs *n = &run->needs;
    if (!n->history_frames && !n->jitter_length && !n->motion_vectors && !ref.history_frames &&
        !ref.jitter_length && !ref.motion_vectors && !dropped)
        return NULL;
    json_t *o = needs_json(n);
    json_object_set_new(
        o, "rule",
        json_string("frame k is a pure function of k: every history starts afresh at the first "
                    "frame an instance draws and history_frames frames before each captured "
                    "frame; the timed run draws those frames in its warm-up and timed frames, "
                    "and the reference and the temporal frames, which start a new instance at "
                    "a captured frame, draw the history_frames frames before it first"));
    if (spec->reference[0]) {
        json_t *r = needs_json(&ref);
        if (dropped)
            json_object_set_new(r, "antialiasing_left_out",
                                json_string("the reference renders the job's look without its "
                                            "anti-aliasing effects (taa): it is the truth they "
                                            "approximate; give reference_look to choose"));
        json_object_set_new(o, "reference", r);
    }
    return o;
}

int run_pass_order(const struct harness_run *run, int *order)
{
    int n = 0;
    if (run->shadow_pass >= 0)
        order[n++] = run->shadow_pass;
    for (int s = 0; s < run->passes.count; s++)
        if (s != run->shadow_pass)
            order[n++] = s;
    return n;
}
