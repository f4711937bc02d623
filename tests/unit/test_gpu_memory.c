/* GPU memory figures through a fake GL reader: GL_NVX_gpu_memory_info
 * preferred, GL_ATI_meminfo's four values per pool, neither (llvmpipe)
 * absent with the reason; and the run's readings as the result shows them. */
#include <string.h>

#include "daemon/gpu/gpu_memory.h"
#include "tests/unit/check.h"

struct fake_gl {
    bool nvx, ati;
    long long available; /* CURRENT_AVAILABLE / TEXTURE_FREE[0], moved by the test */
    long long evictions;
    int queries;
};

static bool fake_has(const char *name, void *ctx)
{
    struct fake_gl *f = ctx;
    return (f->nvx && !strcmp(name, "GL_NVX_gpu_memory_info")) ||
           (f->ati && !strcmp(name, "GL_ATI_meminfo"));
}

static void fake_get(unsigned pname, int *v, void *ctx)
{
    struct fake_gl *f = ctx;
    f->queries++;
    switch (pname) {
    case GPU_MEMORY_NVX_DEDICATED_VIDMEM: v[0] = 81559 * 1024; break;
    case GPU_MEMORY_NVX_TOTAL_AVAILABLE: v[0] = 81000 * 1024; break;
    case GPU_MEMORY_NVX_CURRENT_AVAILABLE: v[0] = (int)f->available; break;
    case GPU_MEMORY_NVX_EVICTION_COUNT: v[0] = (int)f->evictions; break;
    case GPU_MEMORY_NVX_EVICTED_MEMORY: v[0] = (int)f->evictions * 4096; break;
    case GPU_MEMORY_ATI_VBO_FREE: v[0] = 100, v[1] = 50, v[2] = 7, v[3] = 3; break;
    case GPU_MEMORY_ATI_TEXTURE_FREE:
        v[0] = (int)f->available, v[1] = 60, v[2] = 8, v[3] = 4;
        break;
    case GPU_MEMORY_ATI_RENDERBUFFER_FREE: v[0] = 300, v[1] = 70, v[2] = 9, v[3] = 5; break;
    default: v[0] = -99; /* a pname the code should not ask */
    }
}

static long long num(const json_t *o, const char *a, const char *b)
{
    const json_t *v = json_object_get(o, a);
    if (b)
        v = json_object_get(v, b);
    return json_integer_value(v);
}

int main(void)
{
    struct fake_gl gl = {.nvx = true, .ati = true, .available = 80000 * 1024};
    struct gpu_memory_reader r = {fake_has, fake_get, &gl};
    struct gpu_memory_sample s[3];
    /* NVX wins where both are exposed (Mesa's radeonsi has both). */
    gpu_memory_read(&r, &s[0]);
    CHECK(s[0].source == GPU_MEMORY_NVX && gl.queries == 5);
    CHECK(s[0].dedicated_kib == 81559LL * 1024 && s[0].total_available_kib == 81000LL * 1024 &&
          s[0].available_kib == 80000LL * 1024 && s[0].eviction_count == 0);
    gl.available -= 512 * 1024; /* the set-up took 512 MiB */
    gpu_memory_read(&r, &s[1]);
    gl.evictions = 3;
    gpu_memory_read(&r, &s[2]);
    json_t *j = gpu_memory_run_json(s, 1.5e6, false);
    CHECK(!strcmp(json_string_value(json_object_get(j, "source")), "GL_NVX_gpu_memory_info"));
    CHECK(num(j, "available_kib", "before_setup") == 80000LL * 1024 &&
          num(j, "available_kib", "after_setup") == 79488LL * 1024);
    CHECK(num(j, "setup_kib", NULL) == 512 * 1024);
    CHECK(num(j, "evictions_during_frames", "count") == 3 &&
          num(j, "evictions_during_frames", "kib") == 3 * 4096);
    CHECK(json_real_value(json_object_get(j, "pool_bytes")) == 1.5e6 && !json_object_get(j, "reason"));
    json_decref(j);

    /* ATI alone: four values per pool, the texture pool's total is what is
     * available, no total or dedicated figure. */
    gl = (struct fake_gl){.ati = true, .available = 2000000};
    gpu_memory_read(&r, &s[0]);
    CHECK(s[0].source == GPU_MEMORY_ATI && gl.queries == 3);
    CHECK(s[0].texture_free[0] == 2000000 && s[0].texture_free[3] == 4 && s[0].vbo_free[1] == 50 &&
          s[0].renderbuffer_free[2] == 9 && s[0].available_kib == 2000000);
    j = gpu_memory_sample_json(&s[0], false);
    CHECK(!strcmp(json_string_value(json_object_get(j, "source")), "GL_ATI_meminfo"));
    CHECK(json_is_null(json_object_get(j, "dedicated_kib")) &&
          json_is_null(json_object_get(j, "total_available_kib")));
    CHECK(json_integer_value(json_array_get(json_object_get(json_object_get(j, "free_kib"),
                                                            "renderbuffer"), 0)) == 300);
    json_decref(j);
    s[1] = s[0];
    s[1].available_kib -= 1000;
    s[2] = s[1];
    j = gpu_memory_run_json(s, 0, false);
    CHECK(num(j, "setup_kib", NULL) == 1000 && !json_object_get(j, "evictions_during_frames"));
    json_decref(j);

    /* Neither (llvmpipe): no query, and the figures absent with a reason. */
    gl = (struct fake_gl){0};
    gpu_memory_read(&r, &s[0]);
    CHECK(s[0].source == GPU_MEMORY_NONE && gl.queries == 0);
    s[1] = s[2] = s[0];
    j = gpu_memory_run_json(s, 73728, true);
    CHECK(json_is_null(json_object_get(j, "source")) && !json_object_get(j, "available_kib"));
    const char *why = json_string_value(json_object_get(j, "reason"));
    CHECK(why && strstr(why, "neither GL_NVX_gpu_memory_info nor GL_ATI_meminfo") &&
          strstr(why, "software renderer"));
    CHECK(json_real_value(json_object_get(j, "pool_bytes")) == 73728);
    json_decref(j);
    j = gpu_memory_sample_json(&s[0], false);
    why = json_string_value(json_object_get(j, "reason"));
    CHECK(why && !strstr(why, "software"));
    json_decref(j);
    return check_finish("test_gpu_memory");
}
