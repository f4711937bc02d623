/* Camera paths: static (the preset's pose, the asset's camera, or the pose
 * scene.camera states, perspective or orthographic), orbit (circles the
 * bounds' centre at a distance that keeps every bounding sphere in view)
 * and flythrough (a smooth closed loop above the objects, through the light
 * volume, looking ahead and down). Each is a pure function of the frame
 * index: integer arithmetic first (frame mod period), then one angle. */
#include <math.h>
#include <string.h>

#include "daemon/scene/scene_build.h"

static const double PI = 3.14159265358979323846;

void scene_mat4_mul(float out[16], const float a[16], const float b[16])
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

void scene_mat4_transform(const float m[16], const float p[3], float w, float out[4])
{
    for (int row = 0; row < 4; row++)
        out[row] = m[row] * p[0] + m[4 + row] * p[1] + m[8 + row] * p[2] + m[12 + row] * w;
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

/* The view matrix and its inverse. The arithmetic of the view is the one
 * the thesis grid was always rendered with: keep it so, or the grid's
 * pixels change. The inverse is exact by construction (transpose of the
 * rotation, eye as translation) rather than a general inversion. */
static void look_at(float m[16], float inv[16], const float eye[3], const float target[3],
                    const float up[3])
{
    float f[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
    float s[3], u[3];
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
    memset(inv, 0, 16 * sizeof(float));
    for (int i = 0; i < 3; i++) {
        inv[0 + i] = s[i];
        inv[4 + i] = u[i];
        inv[8 + i] = -f[i];
        inv[12 + i] = eye[i];
    }
    inv[15] = 1.0f;
}

/* glFrustum-style perspective and its inverse: clip = (a x, b y, c z + d,
 * -z), so z = -w' and w = (z' + c w') / d. */
static void perspective(float m[16], float inv[16], float fovy_deg, float aspect, float n,
                        float f)
{
    float t = 1.0f / tanf((float)(fovy_deg * PI / 360.0));
    memset(m, 0, 16 * sizeof(float));
    m[0] = t / aspect;
    m[5] = t;
    m[10] = (f + n) / (n - f);
    m[11] = -1.0f;
    m[14] = 2.0f * f * n / (n - f);
    memset(inv, 0, 16 * sizeof(float));
    inv[0] = 1.0f / m[0];
    inv[5] = 1.0f / m[5];
    inv[11] = 1.0f / m[14];
    inv[14] = -1.0f;
    inv[15] = m[10] / m[14];
}

/* glTF's orthographic projection (half-extents xmag, ymag; planes n, f)
 * and its inverse: clip = (x / xmag, y / ymag, 2 z / (n - f) + (f + n) /
 * (n - f), 1). */
static void orthographic(float m[16], float inv[16], float xmag, float ymag, float n, float f)
{
    memset(m, 0, 16 * sizeof(float));
    m[0] = 1.0f / xmag;
    m[5] = 1.0f / ymag;
    m[10] = 2.0f / (n - f);
    m[14] = (f + n) / (n - f);
    m[15] = 1.0f;
    memset(inv, 0, 16 * sizeof(float));
    inv[0] = xmag;
    inv[5] = ymag;
    inv[10] = 0.5f * (n - f);
    inv[14] = -0.5f * (f + n);
    inv[15] = 1.0f;
}

bool scene_camera_moves(const struct scene *s)
{
    return s->spec.camera != SCENE_CAMERA_STATIC && s->spec.camera_period > 1;
}

/* Eye position of the flythrough at angle a (radians): an ellipse around
 * the objects' centre whose height rises and falls twice a loop. */
static void fly_eye(const struct scene *s, double a, float out[3])
{
    const struct scene_rig *r = &s->rig;
    double cx = 0.5 * ((double)s->objects.min[0] + s->objects.max[0]);
    double cz = 0.5 * ((double)s->objects.min[2] + s->objects.max[2]);
    out[0] = (float)(cx + r->fly_radius[0] * sin(a));
    out[1] = (float)(r->fly_height[0] +
                     (r->fly_height[1] - r->fly_height[0]) * (0.5 - 0.5 * cos(2.0 * a)));
    out[2] = (float)(cz + r->fly_radius[1] * cos(a));
}

/* The matrices of a camera whose eye, target, up, fovy and planes are set. */
static void camera_matrices(const struct scene *s, struct scene_camera *c)
{
    look_at(c->view, c->inv_view, c->eye, c->target, c->up);
    if (c->orthographic)
        orthographic(c->proj, c->inv_proj, c->xmag, c->ymag, c->near_z, c->far_z);
    else
        perspective(c->proj, c->inv_proj, c->fovy_deg,
                    (float)s->spec.width / (float)s->spec.height, c->near_z, c->far_z);
    scene_mat4_mul(c->view_proj, c->proj, c->view);
}

/* The orbit camera at azimuth az and distance d. */
static void orbit_camera(const struct scene *s, double az, double d, struct scene_camera *c)
{
    const struct scene_rig *r = &s->rig;
    double el = r->orbit_elevation;
    memset(c, 0, sizeof(*c));
    c->up[1] = 1.0f;
    c->fovy_deg = r->fovy_deg;
    c->near_z = r->near_z;
    c->far_z = r->orbit_far;
    c->eye[0] = (float)(r->centre[0] + d * cos(el) * sin(az));
    c->eye[1] = (float)(r->centre[1] + d * sin(el));
    c->eye[2] = (float)(r->centre[2] + d * cos(el) * cos(az));
    memcpy(c->target, r->centre, sizeof(c->target));
    camera_matrices(s, c);
}

static bool corners_in_view(const struct scene_camera *c, const struct scene_box *b)
{
    for (int corner = 0; corner < 8; corner++) {
        float p[3], v[4];
        for (int k = 0; k < 3; k++)
            p[k] = corner >> k & 1 ? b->max[k] : b->min[k];
        scene_mat4_transform(c->view_proj, p, 1.0f, v);
        if (!(v[3] > 0 && fabsf(v[0]) <= v[3] && fabsf(v[1]) <= v[3] && fabsf(v[2]) <= v[3]))
            return false;
    }
    return true;
}

void scene_camera_at(const struct scene *s, int64_t frame, struct scene_camera *out)
{
    const struct scene_rig *r = &s->rig;
    memset(out, 0, sizeof(*out));
    out->up[1] = 1.0f;
    out->fovy_deg = r->fovy_deg;
    out->near_z = r->near_z;
    out->far_z = r->far_z;
    int64_t period = s->spec.camera_period > 0 ? s->spec.camera_period : 1;
    int64_t step = frame % period;
    if (step < 0)
        step += period;
    double a = 2.0 * PI * (double)step / (double)period;
    switch (s->spec.camera) {
    case SCENE_CAMERA_STATIC:
        memcpy(out->eye, r->eye, sizeof(out->eye));
        memcpy(out->target, r->target, sizeof(out->target));
        if (r->up[0] != 0.0f || r->up[1] != 0.0f || r->up[2] != 0.0f)
            memcpy(out->up, r->up, sizeof(out->up));
        out->orthographic = r->orthographic;
        out->xmag = r->xmag;
        out->ymag = r->ymag;
        break;
    case SCENE_CAMERA_ORBIT:
        orbit_camera(s, r->orbit_azimuth + a, r->orbit_distance, out);
        return;
    case SCENE_CAMERA_FLYTHROUGH: {
        /* Look at a point half-way between the path a little ahead and the
         * objects' centre, down at the objects' mid-height: the view turns
         * with the path and always holds objects. */
        float ahead[3];
        fly_eye(s, a, out->eye);
        fly_eye(s, a + 0.6, ahead);
        out->target[0] = 0.5f * ahead[0] + 0.25f * (s->objects.min[0] + s->objects.max[0]);
        out->target[1] = r->fly_look_y;
        out->target[2] = 0.5f * ahead[2] + 0.25f * (s->objects.min[2] + s->objects.max[2]);
        break;
    }
    }
    camera_matrices(s, out);
}

void scene_rig_derive(struct scene *s)
{
    struct scene_rig *r = &s->rig;
    /* The orbit frames what matters, the objects and the light volume (a
     * ground plane may run out of the picture), from the static pose's
     * elevation: the nearest distance at which the box's corners are all in
     * view, from 72 azimuths, with 3% to spare between them. A sphere
     * around the box would fit from any direction too, but much farther
     * away for flat scenes. */
    struct scene_box fit = s->objects;
    double radius2 = 0;
    for (int k = 0; k < 3; k++) {
        /* An asset's generated lights stand around it, outside: the orbit
         * frames the asset alone. */
        if (!s->asset) {
            fit.min[k] = fminf(fit.min[k], s->light_volume.min[k]);
            fit.max[k] = fmaxf(fit.max[k], s->light_volume.max[k]);
        }
        r->centre[k] = 0.5f * (fit.min[k] + fit.max[k]);
        double half = 0.5 * ((double)fit.max[k] - fit.min[k]);
        radius2 += half * half;
    }
    double radius = sqrt(radius2);
    double to[3] = {(double)r->eye[0] - r->target[0], (double)r->eye[1] - r->target[1],
                    (double)r->eye[2] - r->target[2]};
    double el = asin(to[1] / sqrt(to[0] * to[0] + to[1] * to[1] + to[2] * to[2]));
    r->orbit_elevation = (float)fmin(fmax(el, 0.2), 1.3);
    r->orbit_azimuth = (float)atan2((double)r->eye[0] - r->centre[0],
                                    (double)r->eye[2] - r->centre[2]);
    /* The sphere around the box is in view from radius / sin(smaller half
     * field of view): the bisection's upper end. */
    double half_y = r->fovy_deg * PI / 360.0;
    double half_x = atan((double)s->spec.width / s->spec.height * tan(half_y));
    double far_enough = radius / sin(half_x < half_y ? half_x : half_y) + r->near_z;
    r->orbit_far = (float)fmax(r->far_z, far_enough + radius * 1.05);
    double needed = 0;
    for (int j = 0; j < 72; j++) {
        double az = 2.0 * PI * j / 72.0, lo = 0.0, hi = far_enough;
        for (int step = 0; step < 40; step++) {
            struct scene_camera c;
            double mid = 0.5 * (lo + hi);
            orbit_camera(s, az, mid, &c);
            *(corners_in_view(&c, &fit) ? &hi : &lo) = mid;
        }
        needed = fmax(needed, hi);
    }
    r->orbit_distance = (float)fmin(needed * 1.03, far_enough);

    /* The flythrough loops over the middle of the objects, high enough to
     * clear the tallest one by 1.5 units, and rises towards the top of the
     * light volume (or 3 units more) twice a loop. */
    r->fly_radius[0] = 0.3f * (s->objects.max[0] - s->objects.min[0]);
    r->fly_radius[1] = 0.3f * (s->objects.max[2] - s->objects.min[2]);
    r->fly_height[0] = s->objects.max[1] + 1.5f;
    r->fly_height[1] = fmaxf(s->light_volume.max[1], r->fly_height[0] + 3.0f);
    r->fly_look_y = 0.5f * (s->objects.min[1] + s->objects.max[1]);
}

void scene_apply_pose(struct scene *s)
{
    const struct scene_camera_spec *v = &s->spec.view;
    struct scene_rig *r = &s->rig;
    if (!v->given)
        return;
    for (int k = 0; k < 3; k++) {
        r->eye[k] = (float)v->eye[k];
        r->target[k] = (float)v->target[k];
        r->up[k] = (float)v->up[k];
    }
    if (v->yfov_deg > 0)
        r->fovy_deg = (float)v->yfov_deg;
    r->orthographic = v->orthographic;
    if (v->orthographic) {
        r->ymag = (float)v->ymag;
        r->xmag = v->xmag > 0 ? (float)v->xmag
                              : (float)(v->ymag * s->spec.width / (double)s->spec.height);
    }
    if (v->far_z > 0) {
        r->near_z = (float)v->near_z;
        r->far_z = (float)v->far_z;
        return;
    }
    /* Derived: from just before the nearest point of the bounds' sphere to
     * just past its farthest (a thousandth of the far plane when the eye
     * stands inside it). */
    double c2 = 0, radius2 = 0;
    for (int k = 0; k < 3; k++) {
        double c = 0.5 * ((double)s->bounds.min[k] + s->bounds.max[k]);
        double half = 0.5 * ((double)s->bounds.max[k] - s->bounds.min[k]);
        c2 += (v->eye[k] - c) * (v->eye[k] - c);
        radius2 += half * half;
    }
    double dist = sqrt(c2), radius = fmax(sqrt(radius2), 1e-3) * 1.05;
    r->far_z = (float)(dist + radius);
    r->near_z = (float)fmax(1e-3 * (dist + radius), dist - radius);
}
