/* The light-bounds geometry of the many-lights techniques (GL-free): the
 * tight and loose screen rectangles of light spheres against brute force
 * (many points of each sphere projected), and the cluster grid rule. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/scene/scene.h"
#include "daemon/techniques/shared/culling_info.h"
#include "tests/unit/check.h"

static const double PI = 3.14159265358979323846;

static void project(const float *vp, const float p[3], int w, int h, float out[3])
{
    float c[4];
    for (int r = 0; r < 4; r++)
        c[r] = vp[r] * p[0] + vp[4 + r] * p[1] + vp[8 + r] * p[2] + vp[12 + r];
    out[0] = (c[0] / c[3] * 0.5f + 0.5f) * w;
    out[1] = (c[1] / c[3] * 0.5f + 0.5f) * h;
    out[2] = c[3];
}

int main(void)
{
    struct scene_spec spec;
    scene_spec_defaults(&spec);
    struct scene s;
    CHECK(scene_init(&s, &spec));
    int w = spec.width, h = spec.height;
    srand(7);
    int tight_seen = 0, full = 0, empty = 0;
    for (int n = 0; n < 400; n++) {
        float c[3] = {(float)(rand() % 800) / 10.0f - 40.0f, (float)(rand() % 400) / 10.0f - 5.0f,
                      (float)(rand() % 800) / 10.0f - 60.0f};
        float r = 0.5f + (float)(rand() % 100) / 10.0f;
        int tight[4], loose[4];
        bool t_ok = light_rect(LIGHT_BOUNDS_SCISSOR_TIGHT, c, r, s.view, s.proj, s.view_proj,
                               s.near_z, s.far_z, w, h, tight);
        bool l_ok = light_rect(LIGHT_BOUNDS_SCISSOR_LOOSE, c, r, s.view, s.proj, s.view_proj,
                               s.near_z, s.far_z, w, h, loose);
        /* Brute force: the projections of points on the sphere in front of
         * the near plane, inside the viewport. */
        float lo[2] = {1e30f, 1e30f}, hi[2] = {-1e30f, -1e30f};
        float all_lo[2] = {1e30f, 1e30f}, all_hi[2] = {-1e30f, -1e30f}; /* off screen too */
        bool crosses_near = false, any = false;
        for (int a = 0; a <= 96; a++)
            for (int b = 0; b < 192; b++) {
                double th = PI * a / 96, ph = 2 * PI * b / 192;
                float p[3] = {c[0] + r * (float)(sin(th) * cos(ph)), c[1] + r * (float)cos(th),
                              c[2] + r * (float)(sin(th) * sin(ph))};
                float q[3];
                project(s.view_proj, p, w, h, q);
                if (q[2] <= s.near_z) {
                    crosses_near = true;
                    continue;
                }
                if (q[2] >= s.far_z)
                    continue;
                for (int k = 0; k < 2; k++)
                    all_lo[k] = fminf(all_lo[k], q[k]), all_hi[k] = fmaxf(all_hi[k], q[k]);
                if (q[0] < 0 || q[0] > w || q[1] < 0 || q[1] > h)
                    continue;
                any = true;
                for (int k = 0; k < 2; k++)
                    lo[k] = fminf(lo[k], q[k]), hi[k] = fmaxf(hi[k], q[k]);
            }
        if (!any) {
            empty += !t_ok;
            continue;
        }
        /* Conservative: every projected point lies in both rectangles. */
        CHECK(t_ok && l_ok);
        CHECK(lo[0] >= tight[0] - 0.01f && hi[0] <= tight[2] + 0.01f);
        CHECK(lo[1] >= tight[1] - 0.01f && hi[1] <= tight[3] + 0.01f);
        CHECK(lo[0] >= loose[0] - 0.01f && hi[0] <= loose[2] + 0.01f);
        CHECK(lo[1] >= loose[1] - 0.01f && hi[1] <= loose[3] + 0.01f);
        if (crosses_near) {
            full += tight[0] == 0 && tight[2] == w;
            continue;
        }
        /* Tight: within two pixels of the sampled silhouette, clamped to the
         * viewport (samples miss the exact extremes by a fraction of a
         * pixel), and never larger than the loose box. */
        CHECK(tight[0] >= (int)floorf(fmaxf(all_lo[0], 0)) - 2 &&
              tight[2] <= (int)ceilf(fminf(all_hi[0], (float)w)) + 2);
        CHECK(tight[1] >= (int)floorf(fmaxf(all_lo[1], 0)) - 2 &&
              tight[3] <= (int)ceilf(fminf(all_hi[1], (float)h)) + 2);
        CHECK(tight[0] >= loose[0] && tight[2] <= loose[2]);
        CHECK(tight[1] >= loose[1] && tight[3] <= loose[3]);
        tight_seen++;
    }
    CHECK(tight_seen > 100);
    printf("spheres: %d bounded tightly, %d reaching the near plane, %d off screen\n",
           tight_seen, full, empty);

    struct job_error err;
    CHECK(cluster_grid_check((const int[3]){16, 9, 24}, "c", &err));
    CHECK(cluster_grid_check((const int[3]){1024, 1024, 1}, "c", &err));
    CHECK(!cluster_grid_check((const int[3]){1024, 1024, 2}, "c", &err));
    CHECK(strcmp(err.field, "c.grid") == 0);
    scene_finish(&s);
    return check_finish("test_culling");
}
