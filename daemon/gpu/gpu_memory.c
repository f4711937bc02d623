#include "daemon/gpu/gpu_memory.h"

#include <string.h>

void gpu_memory_read(const struct gpu_memory_reader *r, struct gpu_memory_sample *out)
{
    memset(out, 0, sizeof(*out));
    int v[4];
    if (r->has_extension("GL_NVX_gpu_memory_info", r->ctx)) {
        out->source = GPU_MEMORY_NVX;
        static const unsigned pnames[5] = {
            GPU_MEMORY_NVX_DEDICATED_VIDMEM, GPU_MEMORY_NVX_TOTAL_AVAILABLE,
            GPU_MEMORY_NVX_CURRENT_AVAILABLE, GPU_MEMORY_NVX_EVICTION_COUNT,
            GPU_MEMORY_NVX_EVICTED_MEMORY};
        long long *dst[5] = {&out->dedicated_kib, &out->total_available_kib, &out->available_kib,
                             &out->eviction_count, &out->evicted_kib};
        for (int i = 0; i < 5; i++) {
            v[0] = 0;
            r->get_integers(pnames[i], v, r->ctx);
            *dst[i] = v[0];
        }
        return;
    }
    if (r->has_extension("GL_ATI_meminfo", r->ctx)) {
        out->source = GPU_MEMORY_ATI;
        static const unsigned pnames[3] = {GPU_MEMORY_ATI_VBO_FREE, GPU_MEMORY_ATI_TEXTURE_FREE,
                                           GPU_MEMORY_ATI_RENDERBUFFER_FREE};
        long long *dst[3] = {out->vbo_free, out->texture_free, out->renderbuffer_free};
        for (int i = 0; i < 3; i++) {
            memset(v, 0, sizeof(v));
            r->get_integers(pnames[i], v, r->ctx);
            for (int k = 0; k < 4; k++)
                dst[i][k] = v[k];
        }
        /* Render targets and textures come from the texture pool. */
        out->available_kib = out->texture_free[0];
        out->total_available_kib = -1;
        out->dedicated_kib = -1;
    }
}

static const char *source_name(enum gpu_memory_source s)
{
    return s == GPU_MEMORY_NVX ? "GL_NVX_gpu_memory_info"
           : s == GPU_MEMORY_ATI ? "GL_ATI_meminfo" : NULL;
}

static const char *reason(bool software)
{
    return software ? "the driver exposes neither GL_NVX_gpu_memory_info nor GL_ATI_meminfo: a "
                      "software renderer keeps its buffers in the daemon's own memory (the "
                      "memory budget and result.interference count it)"
                    : "the driver exposes neither GL_NVX_gpu_memory_info nor GL_ATI_meminfo";
}

static json_t *kib_or_null(long long v) { return v >= 0 ? json_integer(v) : json_null(); }

json_t *gpu_memory_sample_json(const struct gpu_memory_sample *s, bool software)
{
    if (s->source == GPU_MEMORY_NONE)
        return json_pack("{s:n, s:s}", "source", "reason", reason(software));
    json_t *j = json_pack("{s:s, s:o, s:o, s:I}", "source", source_name(s->source),
                          "dedicated_kib", kib_or_null(s->dedicated_kib), "total_available_kib",
                          kib_or_null(s->total_available_kib), "available_kib",
                          (json_int_t)s->available_kib);
    if (s->source == GPU_MEMORY_NVX)
        json_object_set_new(j, "evictions", json_pack("{s:I, s:I}", "count",
                                                      (json_int_t)s->eviction_count, "kib",
                                                      (json_int_t)s->evicted_kib));
    else
        json_object_set_new(j, "free_kib",
                            json_pack("{s:[I,I,I,I], s:[I,I,I,I], s:[I,I,I,I]}", "vbo",
                                      s->vbo_free[0], s->vbo_free[1], s->vbo_free[2],
                                      s->vbo_free[3], "texture", s->texture_free[0],
                                      s->texture_free[1], s->texture_free[2], s->texture_free[3],
                                      "renderbuffer", s->renderbuffer_free[0],
                                      s->renderbuffer_free[1], s->renderbuffer_free[2],
                                      s->renderbuffer_free[3]));
    return j;
}

json_t *gpu_memory_run_json(const struct gpu_memory_sample samples[3], double pool_bytes,
                            bool software)
{
    const struct gpu_memory_sample *before = &samples[0], *setup = &samples[1],
                                   *frames = &samples[2];
    if (before->source == GPU_MEMORY_NONE)
        return json_pack("{s:n, s:s, s:f}", "source", "reason", reason(software), "pool_bytes",
                         pool_bytes);
    json_t *j = json_pack(
        "{s:s, s:o, s:o, s:{s:I, s:I, s:I}, s:I, s:f, s:s}", "source",
        source_name(before->source), "dedicated_kib", kib_or_null(before->dedicated_kib),
        "total_available_kib", kib_or_null(before->total_available_kib), "available_kib",
        "before_setup", (json_int_t)before->available_kib, "after_setup",
        (json_int_t)setup->available_kib, "after_frames", (json_int_t)frames->available_kib,
        "setup_kib", (json_int_t)(before->available_kib - setup->available_kib), "pool_bytes",
        pool_bytes, "rule",
        "available_kib as the driver reports it (GL_GPU_MEMORY_INFO_CURRENT_AVAILABLE_VIDMEM_NVX, "
        "or GL_TEXTURE_FREE_MEMORY_ATI's total) before the run's set-up, after it and after the "
        "timed frames; setup_kib is its fall over the set-up (the driver's count, which other "
        "processes on the GPU move too); pool_bytes is the render-target pool's own count of "
        "the targets it holds");
    if (before->source == GPU_MEMORY_NVX)
        json_object_set_new(j, "evictions_during_frames",
                            json_pack("{s:I, s:I}", "count",
                                      (json_int_t)(frames->eviction_count - setup->eviction_count),
                                      "kib",
                                      (json_int_t)(frames->evicted_kib - setup->evicted_kib)));
    return j;
}
