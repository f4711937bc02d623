#include "daemon/scene/scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

/* Thesis layout (chapter 3.1.1): 16 columns, 8 rows, 4 layers; rows alternate
 * between spheres and cubes, giving 8x8x4 of each. */
enum { GRID_COLS = 16, GRID_ROWS = 8, GRID_LAYERS = 4 };
static const float GRID_SPACING_X = 2.5f, GRID_SPACING_Z = 3.0f,
                   GRID_SPACING_Y = 2.5f;
static const float SPHERE_RADIUS = 0.8f, CUBE_HALF = 0.65f;

static void mat4_mul(float out[16], const float a[16], const float b[16])
{
    float r[16];
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            float sum = 0.0f;
            for (int k = 0; k < 4; k++)
                sum += a[k * 4 + row] * b[c * 4 + k];
            r[c * 4 + row] = sum;
        }
    memcpy(out, r, sizeof(r));
}

static void vec3_normalize(float v[3])
{
    float len = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int i = 0; i < 3; i++)
        v[i] /= len;
}

static void vec3_cross(float out[3], const float a[3], const float b[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static void look_at(float m[16], const float eye[3], const float target[3])
{
    float f[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
    float up[3] = {0, 1, 0}, s[3], u[3];
    vec3_normalize(f);
    vec3_cross(s, f, up);
    vec3_normalize(s);
    vec3_cross(u, s, f);
    memset(m, 0, 16 * sizeof(float));
    for (int i = 0; i < 3; i++) {
        m[i * 4 + 0] = s[i];
        m[i * 4 + 1] = u[i];
        m[i * 4 + 2] = -f[i];
    }
    m[12] = -(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]);
    m[13] = -(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]);
    m[14] = f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2];
    m[15] = 1.0f;
}

static void perspective(float m[16], float fovy_deg, float aspect, float n, float f)
{
    float t = 1.0f / tanf((float)(fovy_deg * PI / 360.0));
    memset(m, 0, 16 * sizeof(float));
    m[0] = t / aspect;
    m[5] = t;
    m[10] = (f + n) / (n - f);
    m[11] = -1.0f;
    m[14] = 2.0f * f * n / (n - f);
}

/* Van der Corput radical inverse: an even, deterministic spread of lights. */
static double radical_inverse(unsigned i, unsigned base)
{
    double inv = 1.0 / base, f = inv, r = 0.0;
    for (; i; i /= base, f *= inv)
        r += f * (i % base);
    return r;
}

static void hsv_to_rgb(double h, double s, double v, float out[3])
{
    double c = v * s, hp = fmod(h, 1.0) * 6.0, x = c * (1 - fabs(fmod(hp, 2.0) - 1));
    double r = 0, g = 0, b = 0;
    if (hp < 1) r = c, g = x;
    else if (hp < 2) r = x, g = c;
    else if (hp < 3) g = c, b = x;
    else if (hp < 4) g = x, b = c;
    else if (hp < 5) r = x, b = c;
    else r = c, b = x;
    out[0] = (float)(r + v - c), out[1] = (float)(g + v - c), out[2] = (float)(b + v - c);
}

bool scene_create(struct scene *out, const struct scene_spec *spec)
{
    memset(out, 0, sizeof(*out));
    out->spec = *spec;
    if (!mesh_create_sphere(&out->meshes[SCENE_MESH_SPHERE], SPHERE_RADIUS,
                            spec->sphere_segments) ||
        !mesh_create_cube(&out->meshes[SCENE_MESH_CUBE], CUBE_HALF))
        goto fail;

    out->instance_count = GRID_COLS * GRID_ROWS * GRID_LAYERS;
    out->instances = calloc((size_t)out->instance_count, sizeof(*out->instances));
    out->light_count = spec->lights;
    out->lights = calloc((size_t)(spec->lights ? spec->lights : 1), sizeof(*out->lights));
    if (!out->instances || !out->lights)
        goto fail;

    /* Grouped by mesh (spheres first) so each mesh is one instanced draw. */
    int next = 0;
    for (int mesh = 0; mesh < SCENE_MESH_COUNT; mesh++) {
        for (int layer = 0; layer < GRID_LAYERS; layer++)
            for (int row = 0; row < GRID_ROWS; row++) {
                if (row % 2 != mesh)
                    continue;
                for (int col = 0; col < GRID_COLS; col++) {
                    struct scene_instance *in = &out->instances[next++];
                    in->pos[0] = ((float)col - (GRID_COLS - 1) * 0.5f) * GRID_SPACING_X;
                    in->pos[1] = (float)layer * GRID_SPACING_Y;
                    in->pos[2] = -(float)row * GRID_SPACING_Z;
                    in->scale = 1.0f;
                    in->mesh = (enum scene_mesh)mesh;
                    unsigned cell = (unsigned)((layer * GRID_ROWS + row) * GRID_COLS + col);
                    hsv_to_rgb(radical_inverse(cell + 1, 2), 0.45, 0.85, in->albedo);
                }
            }
        out->mesh_instance_count[mesh] = next - (mesh ? out->mesh_instance_count[0] : 0);
    }

    for (int i = 0; i < out->light_count; i++) {
        struct scene_light *l = &out->lights[i];
        unsigned k = (unsigned)i + 1;
        l->centre[0] = (float)((radical_inverse(k, 2) - 0.5) * 40.0);
        l->centre[1] = (float)(radical_inverse(k, 3) * 10.0 - 0.5);
        l->centre[2] = (float)(1.5 - radical_inverse(k, 5) * 24.0);
        l->orbit = 3.0f;
        /* Radius 5 reaches about 100 objects a frame at async distance 20,
         * close to the 90 the thesis reports (chapter 4.1). */
        l->radius = 5.0f;
        hsv_to_rgb(i * 0.618033988749895, 0.6, 1.6, l->color);
        /* Whole frames per revolution keep positions exact for any frame
         * index; light_speed divides the period (0 holds the lights still). */
        int base_period = 180 + 40 * (i % 7);
        l->period = spec->light_speed > 0
                        ? (int)fmax(1.0, lround(base_period / spec->light_speed))
                        : base_period;
        l->phase = (i * 37) % base_period % l->period;
    }

    out->eye[0] = 0.0f, out->eye[1] = 28.0f, out->eye[2] = 22.0f;
    out->target[0] = 0.0f, out->target[1] = 1.0f, out->target[2] = -10.0f;
    out->fovy_deg = 55.0f;
    out->near_z = 0.5f;
    out->far_z = 200.0f;
    look_at(out->view, out->eye, out->target);
    perspective(out->proj, out->fovy_deg, (float)spec->width / (float)spec->height,
                out->near_z, out->far_z);
    mat4_mul(out->view_proj, out->proj, out->view);
    return true;
fail:
    scene_finish(out);
    return false;
}

void scene_finish(struct scene *s)
{
    if (!s)
        return;
    for (int m = 0; m < SCENE_MESH_COUNT; m++)
        mesh_finish(&s->meshes[m]);
    free(s->instances);
    free(s->lights);
    memset(s, 0, sizeof(*s));
}

void scene_light_position(const struct scene *s, int light, int64_t frame,
                          float out[3])
{
    const struct scene_light *l = &s->lights[light];
    int64_t t = s->spec.dynamic && s->spec.light_speed > 0 ? frame : 0;
    int64_t step = (t + l->phase) % l->period;
    if (step < 0)
        step += l->period;
    /* Integer frame arithmetic first, so the angle never loses precision
     * however long the run is. */
    double a = 2.0 * PI * (double)step / (double)l->period;
    out[0] = l->centre[0] + l->orbit * (float)cos(a);
    out[1] = l->centre[1] + l->orbit * (float)sin(a);
    out[2] = l->centre[2];
}

float scene_instance_bound(const struct scene *s, int i)
{
    const struct scene_instance *in = &s->instances[i];
    return s->meshes[in->mesh].bound_radius * in->scale;
}

float scene_instance_distance(const struct scene *s, int i)
{
    const float *p = s->instances[i].pos;
    float d[3] = {p[0] - s->eye[0], p[1] - s->eye[1], p[2] - s->eye[2]};
    return sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

float scene_projected_diameter(const struct scene *s, int i)
{
    float dist = scene_instance_distance(s, i), r = scene_instance_bound(s, i);
    float half_height_px = 0.5f * (float)s->spec.height;
    float tan_half = tanf((float)(s->fovy_deg * PI / 360.0));
    return 2.0f * r / (dist * tan_half) * half_height_px;
}

uint64_t scene_triangles(const struct scene *s)
{
    uint64_t total = 0;
    for (int m = 0; m < SCENE_MESH_COUNT; m++)
        total += (uint64_t)s->mesh_instance_count[m] * (s->meshes[m].index_count / 3);
    return total;
}

bool scene_all_in_view(const struct scene *s)
{
    const float *m = s->view_proj;
    for (int i = 0; i < s->instance_count; i++) {
        const float *p = s->instances[i].pos;
        float r = scene_instance_bound(s, i);
        /* Gribb-Hartmann planes from the combined matrix. */
        for (int plane = 0; plane < 6; plane++) {
            int row = plane / 2;
            float sign = plane % 2 ? -1.0f : 1.0f, eq[4];
            for (int c = 0; c < 4; c++)
                eq[c] = m[c * 4 + 3] + sign * m[c * 4 + row];
            float len = sqrtf(eq[0] * eq[0] + eq[1] * eq[1] + eq[2] * eq[2]);
            float dist = (eq[0] * p[0] + eq[1] * p[1] + eq[2] * p[2] + eq[3]) / len;
            if (dist < r)
                return false;
        }
    }
    return true;
}
