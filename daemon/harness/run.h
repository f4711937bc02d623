#ifndef SHADEBENCH_RUN_H
#define SHADEBENCH_RUN_H

/* One run of a job on the render thread, and the render-thread state every
 * run shares. A run is prepared (scene, targets, the look's stages, the
 * technique and its passes, capture buffers: run_prepare), measured
 * (measure.h), written out (outputs.h) and finished (run_finish); the
 * reference render (reference.h) borrows the measured run's scene and look.
 * The job loop and repeats are runner.c's. Render thread only. */

#include <epoxy/gl.h>
#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/effects/post_chain.h"
#include "daemon/gpu/caps.h"
#include "daemon/gpu/gpu_scene.h"
#include "daemon/gpu/glutil.h"
#include "daemon/gpu/gpu_timer.h"
#include "daemon/gpu/pass.h"
#include "daemon/scene/environment.h"
#include "daemon/gpu/targets.h"
#include "daemon/status/interference.h"
#include "daemon/harness/motion.h"
#include "daemon/harness/transparent.h"
#include "daemon/jobs/queue.h"
#include "daemon/look/look.h"
#include "daemon/scene/scene.h"
#include "daemon/techniques/technique.h"

/* Frames the GPU may run behind the CPU, as a double-buffered swap chain allows. */
#define RUN_FRAMES_IN_FLIGHT 2

/* What every job shares on the render thread, made once the context is up:
 * limits, the target pool (re-created only when a size or format changes),
 * the frame block, the resolve programs and the device strings. */
struct harness_gl {
    struct gpu_caps caps;
    struct gpu_targets *targets;
    struct gpu_frame_block frame_block;
    GLuint empty_vao;
    GLuint resolve_progs[LOOK_TONEMAP_COUNT]; /* by look.tonemap (enum look_tonemap) */
    json_t *device_json;     /* the owner's: immutable once made, read by other threads */
};

/* Once the context is current. finish frees the GL objects, not device_json. */
bool harness_gl_init(struct harness_gl *g, char *err, size_t errlen);
void harness_gl_finish(struct harness_gl *g);

/* HDR statistics of one captured frame. */
struct hdr_stats {
    long long nonfinite; /* pixels with a NaN or infinite R, G or B */
    double mean[3];      /* of the finite pixels */
    double min, max;     /* smallest and largest finite channel */
};

/* One captured frame, as read back in the capture bracket of the timed
 * loop and encoded after it. */
struct run_capture {
    int frame;
    uint8_t *pixels;                 /* the 8-bit frame, RGBA */
    struct post_nonfinite nonfinite; /* of the HDR colour the resolve read */
    struct hdr_stats hdr;            /* physically based looks (run->hdr_scratch set) */
    uint32_t *heat;                  /* light evaluations per pixel, when published */
    /* The harness's motion vectors at that frame, when drawn: their mean
     * (pixels), the longest, and the pixels that moved at all. */
    struct {
        double mean[2], max;
        long long moving;
    } motion;
};

/* How a job's timed frames are drawn, decided once per job in its first
 * run (measure.c) and followed by its later runs: whole (the guard never
 * touches them) or, for a job that accepted sliced timing, in the tiles its
 * measure gave. With the figures that decided it, for the result and for
 * the failure of a job whose whole frame is over the bound. */
struct run_timing_rule {
    bool decided;
    enum gpu_budget_mode mode;  /* GPU_BUDGET_WHOLE or GPU_BUDGET_SLICED */
    double limit_s;             /* job_spec_max_frame_seconds(); 0: no bound */
    int measuring_frames;       /* frames drawn in slices to measure it (1 to 4) */
    double estimate_s[2];       /* the measures' cost drawn whole (a given-up one: what it
                                 * came to when given up; a third overwrites the second);
                                 * -1: none */
    double settling_frame_s;    /* after a give-up, what drawing the frame through in slices,
                                 * unjudged, took; -1: none */
    double whole_frame_s;       /* the deciding frame, drawn whole; -1: none drawn */
    double pixel_share;         /* of the last measured frame's cost, the pixels' work */
    char largest[64];           /* the dearest piece's pass, by the measure */
    double largest_s;
    /* The measures of the first run's pieces, lent to the later runs. */
    struct gpu_budget_piece pieces[GPU_BUDGET_KEYS];
};

struct harness_run {
    struct harness_gl *gl;
    struct queue *queue;
    struct job *job;
    const struct job_spec *spec;
    const struct technique *tech;
    /* The look this run renders with: the job's, or its reference_look, or
     * (a technique that reads no light) look_unlit, that look without its
     * shadow maps and probes. */
    const struct look_spec *look;
    struct look_spec look_unlit;
    struct scene scene;
    bool scene_ok;
    /* scene.asset: the cache file's asset, read in run_prepare (never in a
     * timed region), which the scene borrows until run_finish. */
    struct asset *asset;
    /* look.ibl.environment {"asset": ...}: its image, read likewise and
     * kept until run_finish (the look's sky uploads it). */
    struct environment_image environment;
    /* Asset scenes, set-up before the warm-up: reading the cache file, and
     * building the scene and its GL objects (textures with their mipmaps,
     * buffers) up to a glFinish. */
    double asset_read_ms, scene_upload_ms;
    struct gpu_scene gpu;
    struct gpu_timer *timer;
    struct gpu_passes passes;
    int resolve_pass;
    /* The look's stages (probes, shadow maps, sky): owned by the run that
     * measures; the reference borrows them. */
    struct look_stages stages;
    int shadow_pass, sky_pass; /* -1 when the look has none */
    /* The blended meshes' pass after the sky (transparent.h): owned by the
     * run that measures, borrowed by the reference; -1 without blended
     * materials. */
    struct transparent transparent;
    int transparent_pass;
    struct post_chain *post;
    GLuint hdr_resolved; /* the HDR colour the resolve reads this frame */
    /* Bounded submissions: asks the job's cancel flag and timeout. */
    struct gpu_budget budget;
    /* Zeroed with the run, so that a still camera's block is built once. */
    struct gpu_frame_data frame_data;
    GLuint ldr_fbo;
    /* The output is scale times the job's width and height (a supersampled
     * reference, reference.c); 0 or 1: the job's size. */
    int scale;
    /* The single-sample HDR output the post chain, the HDR statistics and
     * the resolve read: the technique's own at msaa 1, else what the MSAA
     * resolve (msaa_pass) writes from the technique's multisampled output. */
    GLuint hdr_fbo, hdr_color, hdr_depth;
    int msaa_pass; /* -1 at msaa 1 */
    /* The frame contract's time (common/frame_needs.h, gpu/pass.h): what
     * the technique and the post chain need, merged; the harness's motion
     * vectors where they are read (motion_pass -1 otherwise); whether the
     * instance has drawn a frame and which it drew last (the next frame
     * after a gap, or the first, restarts every history); this frame's
     * time, as the technique and the effects are told it. */
    struct frame_needs needs;
    struct motion_vectors motion;
    int motion_pass;
    bool drawn;
    int64_t last_frame;
    struct gpu_frame_time time;
    struct technique_env env;
    struct technique_products products;
    char defines[512];
    void *state;
    /* The captures (the first run of a job only): capture_count slots, the
     * first `captured` of them filled. */
    int capture_count, captured;
    struct run_capture *capture;
    float *hdr_scratch; /* physically based looks: one HDR frame, for the statistics */
    float *motion_scratch; /* motion vectors drawn: one frame's (RG), for their statistics */
    /* The job's timing rule (its owner: the job's first run decides it). */
    struct run_timing_rule *rule;
    bool measuring; /* drawing the harness's measuring frames (for messages) */
    /* Figures of the timed frames. */
    unsigned char *drawn_whole; /* per timed frame: no piece of it drawn in tiles */
    int64_t pieces_sliced;      /* runs of a piece drawn in tiles in the timed frames */
    double *cpu_ms;
    double *frame_ms;
    double wall_s, capture_s;
    struct interference_sample interference[2]; /* start and end of the timed region */
    /* The costs beside the frame times: the programs the set-up and warm-up
     * built (glutil.h), and GPU memory before the set-up, after it and
     * after the frames (gpu_memory.h). */
    struct gl_build_log builds;
    struct gpu_memory_sample gpu_memory[3];
    GLsync fences[RUN_FRAMES_IN_FLIGHT];
    char err[1024];
};

/* Everything before the first frame: the scene, the targets, the look's
 * stages, the technique with its passes and timer, the post chain, and the
 * capture buffers when capture is set (the first run of a job). The run
 * must be zeroed but for gl, queue, job, spec and tech. False with run->err. */
bool run_prepare(struct harness_run *run, bool capture);
/* Frees what run_prepare and the frames made. Takes a run in any state. */
void run_finish(struct harness_run *run);
/* The technique made anew (a frame it was abandoned in may have left its
 * state half-updated: OSL's first shading cut short would read as done).
 * False with run->err. */
bool run_recreate_technique(struct harness_run *run);

/* The output targets and the technique's env for run->look over the run's
 * scene (the reference calls it with the measured run's scene). */
bool run_setup_targets(struct harness_run *run);
/* The technique's passes (its own, the look's shadows and sky, the post
 * chain's, then the resolve) and a timer for timed_frames frames. */
bool run_setup_passes(struct harness_run *run, const void *options, int64_t timed_frames);

/* MSAA (daemon/harness/msaa.c): the multisampled output a technique draws
 * into at spec->msaa samples, w x h (a supersampled reference's size too),
 * made beside the single-sample one (out,
 * color and depth are replaced by the multisampled ones, samples by the
 * count the driver gave, which may be more), false with
 * run->err when the device cannot; and the timed pass that resolves it into
 * run->hdr_fbo: colour averaged, depth (and stencil) from one sample, as
 * glBlitFramebuffer resolves them, for the post chain's depth readers. */
bool run_msaa_targets(struct harness_run *run, GLenum hdr_format, int w, int h, int *samples,
                      GLuint *out, GLuint *color, GLuint *depth);
void run_msaa_resolve(struct harness_run *run);
/* The result's "msaa" object: samples, the reference's, how it resolves. */
json_t *run_msaa_json(const struct harness_run *run);

/* Builds the post chain's effects once the technique was created: the
 * normals it publishes (if any) choose their programs. */
bool run_build_post_chain(struct harness_run *run);

/* Starts the run's budget: its waits ask whether the job was cancelled (a
 * DELETE, or the daemon stopping) or ran out of time. */
void run_budget_init(struct harness_run *run);

/* The per-frame block for frame k: camera (jittered by jitter, in
 * pixels; prev_jitter is the frame before's), the unjittered camera of
 * frame k and of frame k - 1, viewport and counts. */
void run_frame_data(const struct harness_run *run, int64_t k, const float jitter[2],
                    const float prev_jitter[2], struct gpu_frame_data *d);
/* Whether frame k starts every history afresh: the instance's first frame,
 * one after a gap, and the frame needs.history_frames before each captured
 * frame (so that frame k is a pure function of k). */
bool run_history_restarts(const struct harness_run *run, int64_t k);
/* One frame of every stage, from the look's before-passes to the resolve,
 * between the timer's begin and end of frame. Timed. */
bool run_frame(struct harness_run *run, int64_t k, bool timed);

/* The result's "time" object: what the technique and the look's chain
 * (and the reference's) need of time, and how frame k stays a pure
 * function of k; NULL when neither needs anything. */
json_t *run_time_json(const struct harness_run *run);

/* Passes in the order a frame runs them (the shadow pass first); returns
 * the count. */
int run_pass_order(const struct harness_run *run, int *order);

#endif
