#include "daemon/techniques/shared/culling_info.h"

#include "daemon/lighting/look_spec.h"

#include <math.h>
#include <stdio.h>

const char *const gbuffer_normal_choices[] = {"octahedral", "float3", "xy_reconstruct_z", NULL};
const char *const gbuffer_albedo_choices[] = {"rgba8", "pack_shift", "pack_base10", NULL};
const char *const light_bounds_choices[] = {"scissor_tight", "scissor_loose", "volume",
                                            "fullscreen", NULL};
const char *const light_binning_choices[] = {"gpu", "cpu", NULL};
const char *const cluster_slices_choices[] = {"linear", "exponential", NULL};
const char *const cluster_overflow_choices[] = {"fallback", "fail", NULL};
const int cluster_grid_default[3] = {32, 18, 32};

bool cluster_grid_check(const int grid[3], const char *prefix, struct job_error *err)
{
    char field[64];
    snprintf(field, sizeof(field), "%s.grid", prefix);
    double cells = (double)grid[0] * grid[1] * grid[2];
    if (cells > CLUSTER_GRID_MAX_CELLS)
        return job_error_set(err, field,
                             "%d x %d x %d = %.0f clusters; at most %d (the light grid would "
                             "outgrow any device's buffers)",
                             grid[0], grid[1], grid[2], cells, CLUSTER_GRID_MAX_CELLS);
    return true;
}

/* Column-major m times (x, y, z, 1). */
static void transform(const float m[16], const float p[3], float out[4])
{
    for (int r = 0; r < 4; r++)
        out[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
}

/* The NDC range along one axis of a sphere that lies wholly beyond the near
 * plane: the two planes through the eye tangent to it, found in the plane of
 * that axis and z (where the sphere projects to a circle). p_scale and
 * p_shift are the projection's diagonal and off-centre terms for the axis. */
static void tangent_range(float ca, float cz, float r, float p_scale, float p_shift, float *lo,
                          float *hi)
{
    float len2 = ca * ca + cz * cz, len = sqrtf(len2);
    float t = sqrtf(len2 - r * r);
    float cos_t = t / len, sin_t = r / len;
    float v[2];
    for (int s = 0; s < 2; s++) {
        float sn = s ? -sin_t : sin_t;
        /* The tangent point: c rotated by +-theta, scaled by cos(theta). */
        float ta = (ca * cos_t - cz * sn) * cos_t;
        float tz = (ca * sn + cz * cos_t) * cos_t;
        v[s] = (p_scale * ta + p_shift * tz) / -tz;
    }
    *lo = fminf(v[0], v[1]);
    *hi = fmaxf(v[0], v[1]);
}

static bool to_pixels(float nx0, float nx1, float ny0, float ny1, int w, int h, int rect[4])
{
    double x0 = floor((nx0 * 0.5 + 0.5) * w), x1 = ceil((nx1 * 0.5 + 0.5) * w);
    double y0 = floor((ny0 * 0.5 + 0.5) * h), y1 = ceil((ny1 * 0.5 + 0.5) * h);
    rect[0] = (int)fmax(0.0, fmin(w, x0));
    rect[1] = (int)fmax(0.0, fmin(h, y0));
    rect[2] = (int)fmax(0.0, fmin(w, x1));
    rect[3] = (int)fmax(0.0, fmin(h, y1));
    return rect[0] < rect[2] && rect[1] < rect[3];
}

bool light_rect(int kind, const float world_centre[3], float radius, const float view[16],
                const float proj[16], const float view_proj[16], float near_z, float far_z, int w,
                int h, int rect[4])
{
    float c[4];
    transform(view, world_centre, c);
    rect[0] = rect[1] = rect[2] = rect[3] = 0;
    /* Wholly on the eye's side of the near plane, or beyond the far plane. */
    if (c[2] - radius >= -near_z || c[2] + radius <= -far_z)
        return false;
    if (c[2] + radius > -near_z) {
        rect[2] = w, rect[3] = h;
        return true;
    }
    if (kind == LIGHT_BOUNDS_SCISSOR_LOOSE) {
        float nx0 = INFINITY, nx1 = -INFINITY, ny0 = INFINITY, ny1 = -INFINITY;
        for (int i = 0; i < 8; i++) {
            float corner[3], clip[4];
            for (int a = 0; a < 3; a++)
                corner[a] = world_centre[a] + ((i >> a) & 1 ? radius : -radius);
            transform(view_proj, corner, clip);
            if (clip[3] <= 1e-6f) {
                /* A corner at or behind the eye: its projection means nothing. */
                rect[2] = w, rect[3] = h;
                return true;
            }
            nx0 = fminf(nx0, clip[0] / clip[3]), nx1 = fmaxf(nx1, clip[0] / clip[3]);
            ny0 = fminf(ny0, clip[1] / clip[3]), ny1 = fmaxf(ny1, clip[1] / clip[3]);
        }
        return to_pixels(nx0, nx1, ny0, ny1, w, h, rect);
    }
    float nx0, nx1, ny0, ny1;
    tangent_range(c[0], c[2], radius, proj[0], proj[8], &nx0, &nx1);
    tangent_range(c[1], c[2], radius, proj[5], proj[9], &ny0, &ny1);
    return to_pixels(nx0, nx1, ny0, ny1, w, h, rect);
}

double gbuffer_planes_bpp(const struct gbuffer_options *opt, const struct look_spec *look,
                          bool textured, int samples)
{
    /* The formats gbuffer_init picks: albedo 4 bytes (rgba8 or one float);
     * normal RGBA32F (float3), else two channels (RG16_SNORM where the
     * device renders to it, else RG32F: the larger is charged); material
     * RGBA32F under PBR, else RG32F; surface RGBA16F in textured scenes;
     * with MSAA the edge stencil (DEPTH24_STENCIL8). */
    double normal = opt->normal == GBUFFER_NORMAL_FLOAT3 ? 16.0 : 8.0;
    double material = look->lighting == LOOK_PBR ? 16.0 : 8.0;
    double per_sample = 4.0 + normal + material + (textured ? 8.0 : 0.0) + (samples > 1 ? 4.0 : 0.0);
    return per_sample * (samples > 1 ? samples : 1);
}
