#ifndef SHADEBENCH_GPU_MEMORY_H
#define SHADEBENCH_GPU_MEMORY_H

/* GPU memory as the driver reports it: GL_NVX_gpu_memory_info (NVIDIA, and
 * Mesa's radeonsi) or GL_ATI_meminfo (AMD), read through a reader so that
 * the parsing is GL-free and tested with a fake one (caps.c has the GL
 * reader). Where the driver has neither (llvmpipe), a sample says so, and
 * the result's figures are absent with the reason. Pure; any thread. */

#include <jansson.h>
#include <stdbool.h>

/* The extensions' enums, so that this file needs no GL header. */
#define GPU_MEMORY_NVX_DEDICATED_VIDMEM 0x9047
#define GPU_MEMORY_NVX_TOTAL_AVAILABLE 0x9048
#define GPU_MEMORY_NVX_CURRENT_AVAILABLE 0x9049
#define GPU_MEMORY_NVX_EVICTION_COUNT 0x904A
#define GPU_MEMORY_NVX_EVICTED_MEMORY 0x904B
#define GPU_MEMORY_ATI_VBO_FREE 0x87FB
#define GPU_MEMORY_ATI_TEXTURE_FREE 0x87FC
#define GPU_MEMORY_ATI_RENDERBUFFER_FREE 0x87FD

struct gpu_memory_reader {
    bool (*has_extension)(const char *name, void *ctx);
    /* glGetIntegerv: one value for the NVX enums, four for the ATI ones. */
    void (*get_integers)(unsigned pname, int *values, void *ctx);
    void *ctx;
};

enum gpu_memory_source { GPU_MEMORY_NONE, GPU_MEMORY_NVX, GPU_MEMORY_ATI };

/* One reading, in KiB as both extensions count. */
struct gpu_memory_sample {
    enum gpu_memory_source source;
    long long dedicated_kib, total_available_kib, available_kib; /* NVX; ATI: available only */
    long long eviction_count, evicted_kib;                       /* NVX */
    /* ATI: the free memory of each pool: total free, largest free block,
     * total auxiliary free, largest auxiliary block. */
    long long vbo_free[4], texture_free[4], renderbuffer_free[4];
};

/* NVX where the driver has it (it says more), else ATI, else none. */
void gpu_memory_read(const struct gpu_memory_reader *r, struct gpu_memory_sample *out);

/* A reading alone (/v1/info's device.gpu_memory): source, the figures, or
 * "source": null and a reason. New reference. */
json_t *gpu_memory_sample_json(const struct gpu_memory_sample *s, bool software);

/* The result's "gpu_memory": the readings before the run's set-up, after
 * it and after the timed frames; what the set-up took (setup_kib: the
 * fall in available memory) and the evictions during the frames (NVX),
 * beside pool_bytes, the render-target pool's own count. Without a
 * source: the reason, and pool_bytes alone. New reference. */
json_t *gpu_memory_run_json(const struct gpu_memory_sample samples[3], double pool_bytes,
                            bool software);

#endif
