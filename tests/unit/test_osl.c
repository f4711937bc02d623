#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/techniques/osl/osl_atlas.h"
#include "daemon/techniques/osl/osl_schedule.h"
#include "daemon/scene/mesh_charts.h"
#include "daemon/scene/scene.h"
#include "tests/unit/check.h"

static void check_packing(const int *sizes, int n, int w, int h, const struct atlas_tile *t)
{
    for (int i = 0; i < n; i++) {
        CHECK(t[i].size == sizes[i]);
        CHECK(t[i].x >= 0 && t[i].y >= 0 && t[i].x + t[i].size <= w && t[i].y + t[i].size <= h);
        CHECK(t[i].x % t[i].size == 0 && t[i].y % t[i].size == 0);
        for (int j = i + 1; j < n; j++) {
            bool apart = t[i].x + t[i].size <= t[j].x || t[j].x + t[j].size <= t[i].x ||
                         t[i].y + t[i].size <= t[j].y || t[j].y + t[j].size <= t[i].y;
            CHECK(apart);
        }
    }
}

static void test_atlas(void)
{
    enum { N = 512 };
    int sizes[N];
    struct atlas_tile tiles[N];
    int w, h;
    char err[256];
    for (int i = 0; i < N; i++)
        sizes[i] = 256;
    /* The thesis: 512 tiles of 256x256 = two 4096x4096 mega textures. */
    CHECK(osl_atlas_pack(sizes, N, 16384, 1e12, tiles, &w, &h, err, sizeof(err)));
    CHECK(w == 8192 && h == 4096);
    check_packing(sizes, N, w, h, tiles);

    /* Mixed sizes in scrambled order still pack tightly and never overlap. */
    static const int pool[] = {8, 1024, 64, 16, 256, 32, 128, 8, 512};
    double area = 0;
    for (int i = 0; i < N; i++) {
        sizes[i] = pool[(i * 7) % 9];
        area += (double)sizes[i] * sizes[i];
    }
    CHECK(osl_atlas_pack(sizes, N, 16384, 1e12, tiles, &w, &h, err, sizeof(err)));
    check_packing(sizes, N, w, h, tiles);
    CHECK((double)w * h < 2 * area + 1);

    /* Too big for the device, or for the memory limit: a clear failure. */
    for (int i = 0; i < N; i++)
        sizes[i] = 1024;
    CHECK(!osl_atlas_pack(sizes, N, 16384, 1e12, tiles, &w, &h, err, sizeof(err)));
    CHECK(strstr(err, "osl.resolution") != NULL);
    for (int i = 0; i < N; i++)
        sizes[i] = 256;
    CHECK(!osl_atlas_pack(sizes, N, 4096, 1e12, tiles, &w, &h, err, sizeof(err)));
    CHECK(!osl_atlas_pack(sizes, N, 16384, 64.0 * 1048576, tiles, &w, &h, err, sizeof(err)));
    sizes[3] = 100;
    CHECK(!osl_atlas_pack(sizes, N, 16384, 1e12, tiles, &w, &h, err, sizeof(err)));

    /* Auto sizing: about one texel per pixel, powers of two, clamped. */
    CHECK(osl_auto_tile_size(10.0, 1.0 / 10.0, 1.0) == 128);
    CHECK(osl_auto_tile_size(10.0, 1.0 / 10.0, 2.0) == 256);
    CHECK(osl_auto_tile_size(0.01, 1.0, 1.0) == OSL_TILE_MIN);
    CHECK(osl_auto_tile_size(1e6, 1.0, 1.0) == OSL_TILE_MAX);
    CHECK(osl_auto_tile_size(90.0, 1.0, 1.0) == 64);  /* log2(90) = 6.49 */
    CHECK(osl_auto_tile_size(91.0, 1.0, 1.0) == 128); /* log2(91) = 6.51 */
}

static void test_schedule(void)
{
    /* Thesis 3: "if set to 10 ... an object 35 units away would update every 4th frame". */
    CHECK(osl_period(35.0, 10.0) == 4);
    CHECK(osl_period(9.9, 10.0) == 1);
    CHECK(osl_period(10.0, 10.0) == 2);
    CHECK(osl_period(55.0, 20.0) == 3);
    CHECK(osl_period(1000.0, 0.0) == 1);

    enum { N = 30 };
    double dist[N];
    for (int i = 0; i < N; i++)
        dist[i] = i < 10 ? 5.0 : (i < 20 ? 25.0 : 45.0); /* periods 1, 2, 3 at d = 20 */
    struct osl_schedule s;
    CHECK(osl_schedule_init(&s, dist, N, 20.0));
    CHECK(s.max_period == 3);
    for (int64_t k = -7; k < 40; k++) {
        int due = 0;
        for (int i = 0; i < N; i++) {
            int64_t last = osl_schedule_last(&s, i, k);
            CHECK(last <= k && k - last < s.period[i]);
            CHECK(osl_schedule_due(&s, i, last));
            CHECK(osl_schedule_due(&s, i, k) == (last == k));
            due += osl_schedule_due(&s, i, k);
        }
        /* Staggered: 10 + 10/2 + 10/3 objects a frame, give or take one per group. */
        CHECK(due >= 10 + 5 + 3 && due <= 10 + 5 + 4);
    }
    osl_schedule_finish(&s);
}

static void test_plan(void)
{
    struct {
        struct scene_spec scene;
    } spec;
    scene_spec_defaults(&spec.scene);
    struct scene scene;
    CHECK(scene_init(&scene, &spec.scene));
    int n = scene.instance_count;
    double *dist = malloc((size_t)n * sizeof(double));
    struct osl_work *plan = malloc((size_t)n * sizeof(*plan));
    for (int i = 0; i < n; i++)
        dist[i] = scene_instance_distance(&scene, i);

    /* Static lights: one initial shading, then nothing. */
    struct osl_schedule s0, s20;
    CHECK(osl_schedule_init(&s0, dist, n, 0.0));
    CHECK(osl_schedule_init(&s20, dist, n, 20.0));
    CHECK(osl_schedule_plan(&s0, &scene, 1, true, OSL_RESHADE_TOUCHED, plan) == n);
    for (int k = 2; k < 10; k++)
        CHECK(osl_schedule_plan(&s0, &scene, k, false, OSL_RESHADE_ALL, plan) == 0);
    scene_finish(&scene);

    spec.scene.dynamic = true;
    CHECK(scene_init(&scene, &spec.scene));
    long touched0 = 0, all0 = 0, touched20 = 0;
    for (int k = 1; k <= 60; k++) {
        int t0 = osl_schedule_plan(&s0, &scene, k, false, OSL_RESHADE_TOUCHED, plan);
        for (int j = 0; j < t0; j++) {
            int i = plan[j].instance;
            CHECK(plan[j].time == k);
            CHECK(osl_touched(&scene, i, k) || osl_touched(&scene, i, k - 1));
        }
        touched0 += t0;
        all0 += osl_schedule_plan(&s0, &scene, k, false, OSL_RESHADE_ALL, plan);
        touched20 += osl_schedule_plan(&s20, &scene, k, false, OSL_RESHADE_TOUCHED, plan);
    }
    CHECK(all0 == 60L * n);           /* the thesis's every-object reshading */
    CHECK(touched0 > 0 && touched0 < all0);
    CHECK(touched20 < touched0);       /* async distance reshades less */

    /* Initial shading at any frame uses each object's last due frame. */
    int count = osl_schedule_plan(&s20, &scene, 100, true, OSL_RESHADE_TOUCHED, plan);
    CHECK(count == n);
    for (int j = 0; j < count; j++)
        CHECK(plan[j].time == osl_schedule_last(&s20, plan[j].instance, 100));
    osl_schedule_finish(&s0);
    osl_schedule_finish(&s20);
    scene_finish(&scene);
    free(dist);
    free(plan);
}

/* A triangle covering the texels x + y <= 6 of an 8x8 entry: a pass fills
 * the uncovered texels with a covered 8-neighbour (two diagonals) with the
 * neighbours' mean; the next pass two more; covered texels never change. */
static void test_dilate(void)
{
    enum { S = 8 };
    float pos[S * S * 4] = {0}, nrm[S * S * 4] = {0};
    for (int y = 0; y < S; y++)
        for (int x = 0; x < S; x++)
            if (x + y < S - 1) { /* below the anti-diagonal */
                float *p = &pos[(y * S + x) * 4], *n = &nrm[(y * S + x) * 4];
                p[0] = (float)x, p[1] = (float)y, p[2] = 0.0f, p[3] = 1.0f;
                n[2] = 1.0f;
            }
    long first = osl_dilate_geometry(pos, nrm, NULL, 0, S, 1, NULL);
    CHECK(first == 15); /* x + y == 7 (8 texels) and x + y == 8 (7) */
    for (int y = 0; y < S; y++)
        for (int x = 0; x < S; x++) {
            const float *p = &pos[(y * S + x) * 4];
            CHECK((p[3] == 1.0f) == (x + y <= S));
            if (x + y < S - 1)
                CHECK(p[0] == (float)x && p[1] == (float)y);
            if (x + y == S - 1)
                CHECK(nrm[(y * S + x) * 4 + 2] == 1.0f);
        }
    /* Texel (7, 0)'s covered neighbours were (6, 0) and (6, 1): x mean 6. */
    CHECK(pos[(0 * S + 7) * 4 + 0] == 6.0f);
    /* Texel (7, 1)'s only covered neighbour was (6, 0). */
    CHECK(pos[(1 * S + 7) * 4 + 0] == 6.0f && pos[(1 * S + 7) * 4 + 1] == 0.0f);
    CHECK(osl_dilate_geometry(pos, nrm, NULL, 0, S, 1, NULL) == 11); /* x + y == 9 and 10 */
    CHECK(osl_dilate_geometry(pos, nrm, NULL, 0, S, 8, NULL) == 10); /* the rest, then nothing left */
    float none[S * S * 4] = {0}, none_n[S * S * 4] = {0};
    CHECK(osl_dilate_geometry(none, none_n, NULL, 0, S, 4, NULL) == 0);
}

/* Two charts side by side in an 8x8 level, their rectangles meeting at
 * u = 0.5: chart A covers columns 0 to 2, chart B columns 4 to 7, and
 * column 3 (inside A's rectangle) is uncovered. Filled without owners it
 * takes the mean of both charts' edges (a seam where A's filtering reads
 * it); with owners only A's. */
static void test_dilate_owned(void)
{
    enum { S = 8 };
    static const float rects[2][4] = {{0.0f, 0.0f, 0.5f, 1.0f}, {0.5f, 0.0f, 1.0f, 1.0f}};
    int owner[S * S];
    osl_chart_owners(rects, 2, S, owner);
    CHECK(owner[0] == 0 && owner[3] == 0 && owner[4] == 1 && owner[7 * S + 7] == 1);
    for (int pass = 0; pass < 2; pass++) {
        float pos[S * S * 4] = {0}, nrm[S * S * 4] = {0};
        for (int y = 0; y < S; y++)
            for (int x = 0; x < S; x++)
                if (x != 3) {
                    float *q = &pos[(y * S + x) * 4];
                    q[0] = (float)x, q[3] = 1.0f;
                    nrm[(y * S + x) * 4 + 2] = 1.0f;
                }
        CHECK(osl_dilate_geometry(pos, nrm, NULL, 0, S, 1, pass ? owner : NULL) == S);
        for (int y = 0; y < S; y++)
            CHECK(pos[(y * S + 3) * 4] == (pass ? 2.0f : 3.0f));
    }
    /* A rectangle with no texel centre at this level owns nothing. */
    static const float thin[1][4] = {{0.30f, 0.0f, 0.31f, 1.0f}};
    osl_chart_owners(thin, 1, S, owner);
    long owned = 0;
    for (int i = 0; i < S * S; i++)
        owned += owner[i] >= 0;
    CHECK(owned == 0);
}

/* mesh_chart_rects: two triangles apart in uv are two charts with their
 * own rectangles; a third overlapping the first's rectangle sends both to
 * the whole square (no clamp); shared vertices join triangles. */
static void test_chart_rects(void)
{
    struct mesh_vertex v[9] = {0};
    static const float uv[9][2] = {{0.0f, 0.0f}, {0.4f, 0.0f}, {0.0f, 0.4f},  /* A */
                                   {0.6f, 0.6f}, {1.0f, 0.6f}, {0.6f, 1.0f},  /* B */
                                   {0.1f, 0.1f}, {0.3f, 0.1f}, {0.1f, 0.3f}}; /* C, inside A's box */
    for (int i = 0; i < 9; i++)
        memcpy(v[i].uv, uv[i], sizeof(uv[i]));
    uint32_t idx[9] = {0, 1, 2, 3, 4, 5, 6, 7, 8};
    struct mesh m = {.vertices = v, .indices = idx, .vertex_count = 9, .index_count = 6};
    struct mesh_chart_stats st;
    CHECK(mesh_chart_rects(&m, &st) && st.charts == 2 && st.overlapping == 0);
    CHECK(v[7].chart[0] == 0.0f && v[7].chart[2] == 1.0f); /* in no triangle: no chart */
    CHECK(v[0].chart[0] == 0.0f && v[0].chart[2] == 0.4f && v[2].chart[3] == 0.4f);
    CHECK(v[4].chart[0] == 0.6f && v[4].chart[1] == 0.6f && v[4].chart[2] == 1.0f);
    m.index_count = 9;
    CHECK(mesh_chart_rects(&m, &st) && st.charts == 3 && st.overlapping == 2);
    CHECK(v[0].chart[0] == 0.0f && v[0].chart[2] == 1.0f && v[7].chart[3] == 1.0f);
    CHECK(v[4].chart[0] == 0.6f);
    /* A shared vertex joins two triangles into one chart. */
    uint32_t joined[6] = {0, 1, 2, 1, 3, 4};
    m.indices = joined;
    m.index_count = 6;
    CHECK(mesh_chart_rects(&m, &st) && st.overlapping == 0 && v[3].chart[0] == 0.0f &&
          v[3].chart[2] == 1.0f && v[0].chart[3] == 0.6f);
}

/* Phong's radiance at P with normal N from every light at frame (the
 * shader's light_contribution, lighting.glsl), largest channel of the
 * difference between two frames. */
static double phong_change(const struct scene *sc, int i, const double P[3], const double N[3],
                           const double V[3], int64_t f0, int64_t f1)
{
    const struct scene_instance *in = &sc->instances[i];
    double out[2][3] = {{0}};
    for (int f = 0; f < 2; f++)
        for (int l = 0; l < sc->light_count; l++) {
            float lp[3];
            scene_light_position(sc, l, f ? f1 : f0, lp);
            double Lv[3] = {lp[0] - P[0], lp[1] - P[1], lp[2] - P[2]};
            double d2 = Lv[0] * Lv[0] + Lv[1] * Lv[1] + Lv[2] * Lv[2], r = sc->lights[l].radius;
            if (d2 >= r * r)
                continue;
            double att = 1.0 - d2 / (r * r), d = sqrt(d2);
            double L[3] = {Lv[0] / d, Lv[1] / d, Lv[2] / d};
            double nl = N[0] * L[0] + N[1] * L[1] + N[2] * L[2];
            if (nl <= 0)
                continue;
            double R[3], rv = 0;
            for (int k = 0; k < 3; k++)
                R[k] = -L[k] + 2 * nl * N[k];
            for (int k = 0; k < 3; k++)
                rv += R[k] * V[k];
            double sp = pow(rv > 0 ? rv : 0, in->material.shininess);
            for (int k = 0; k < 3; k++)
                out[f][k] += sc->lights[l].color[k] * att *
                             (in->albedo[k] * nl + in->material.specular * sp);
        }
    double m = 0;
    for (int k = 0; k < 3; k++)
        m = fmax(m, fabs(out[1][k] - out[0][k]));
    return m;
}

/* osl.change_threshold's bound holds: no point of an object, with any
 * normal, changes by more than it says between two frames; objects no
 * light reaches get 0; Phong's motion term makes it tighter than the
 * range term for small moves. */
static void test_change_bound(void)
{
    struct scene_spec spec;
    scene_spec_defaults(&spec);
    spec.dynamic = true;
    struct scene sc;
    CHECK(scene_init(&sc, &spec));
    struct scene_camera cam;
    scene_camera_at(&sc, 0, &cam);
    unsigned seed = 12345;
    int zero = 0, tighter = 0, violations = 0;
    for (int i = 0; i < sc.instance_count; i += 3) {
        for (int gap = 1; gap <= 6; gap += 5) {
            int64_t f0 = 40 + i % 7, f1 = f0 + gap;
            double phong = osl_change_bound(&sc, i, f0, f1, true);
            double range = osl_change_bound(&sc, i, f0, f1, false);
            CHECK(phong <= range + 1e-12);
            zero += range == 0;
            tighter += phong < range;
            double b = scene_instance_bound(&sc, i);
            for (int t = 0; t < 200; t++) {
                double u[3], n[3], len = 0, nlen = 0;
                for (int k = 0; k < 3; k++) {
                    seed = seed * 1103515245u + 12345u;
                    u[k] = ((seed >> 8) & 0xffff) / 32768.0 - 1.0;
                    seed = seed * 1103515245u + 12345u;
                    n[k] = ((seed >> 8) & 0xffff) / 32768.0 - 1.0;
                    len += u[k] * u[k];
                    nlen += n[k] * n[k];
                }
                if (len > 1 || nlen < 1e-6)
                    continue;
                double P[3], N[3], V[3], vlen = 0;
                for (int k = 0; k < 3; k++) {
                    P[k] = sc.instances[i].pos[k] + b * u[k];
                    N[k] = n[k] / sqrt(nlen);
                    V[k] = cam.eye[k] - P[k];
                    vlen += V[k] * V[k];
                }
                for (int k = 0; k < 3; k++)
                    V[k] /= sqrt(vlen);
                violations += phong_change(&sc, i, P, N, V, f0, f1) > phong + 1e-6;
            }
        }
    }
    CHECK(violations == 0);
    CHECK(zero > 0);    /* far from every light */
    CHECK(tighter > 0); /* Phong's motion term pays */
    CHECK(osl_change_bound(&sc, 0, 7, 7, true) == 0);
    scene_finish(&sc);
}

int main(void)
{
    test_dilate();
    test_dilate_owned();
    test_chart_rects();
    test_atlas();
    test_schedule();
    test_plan();
    test_change_bound();
    return check_finish("test_osl");
}
