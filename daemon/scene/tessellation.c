/* sphere_segments "auto": the coarsest sphere whose silhouette stays within
 * scene.tessellation_error_px of the true sphere's, at the largest size any
 * sphere reaches on screen over the camera path.
 *
 * The error bound. A circle of radius r drawn as an n-gon is off by the
 * sagitta r (1 - cos(pi/n)) mid-edge. A lat-long sphere with n segments and
 * n/2 rings is worse than that seen from most directions: next to the
 * equator its faces are planar quads whose corners lie pi/n away in both
 * latitude and longitude, so a face centre sits r cos^2(pi/n) from the
 * centre, and a silhouette that crosses a face there (a view from above
 * the face's diagonal) is r sin^2(pi/n) inside the true one: about twice
 * the n-gon's sagitta. The bound below holds from every direction. */
#include <math.h>

#include "daemon/scene/scene_build.h"

static const double PI = 3.14159265358979323846;

double scene_sphere_error(int segments)
{
    double s = sin(PI / segments);
    return s * s;
}

int scene_auto_segments(double radius_px, double bound_px)
{
    for (int n = 8; n < 256; n += 2)
        if (radius_px * scene_sphere_error(n) <= bound_px)
            return n;
    return 256;
}

float scene_sphere_radius_px(const struct scene_camera *c, int width, int height,
                             const float centre[3], float radius)
{
    float v[4];
    scene_mat4_transform(c->view, centre, 1.0f, v);
    double diag = sqrt((double)width * width + (double)height * height);
    /* Focal length in pixels: the same in x and y for square pixels. */
    double f = c->proj[5] * height * 0.5;
    double x = v[0], y = v[1], z = -v[2], r = radius, rr = r * r;
    if (z * z - rr <= 0.0 || z <= r)
        return (float)diag;
    /* The projection is an ellipse whose major axis points away from the
     * image centre. Turned about the view axis so that the centre lies in
     * the x-z plane, the planes through the eye that contain the y axis and
     * touch the sphere bound it exactly along that axis: the semi-major
     * axis is f r sqrt(x^2 + y^2 + z^2 - r^2) / (z^2 - r^2). */
    double a = f * r * sqrt(x * x + y * y + z * z - rr) / (z * z - rr);
    return (float)fmin(a, diag);
}

void scene_choose_segments(struct scene *s)
{
    const struct scene_spec *spec = &s->spec;
    /* A static camera is one sample; a moving one is sampled at up to 720
     * evenly spaced frames of its period (every frame for shorter loops). */
    int64_t period = scene_camera_moves(s) ? spec->camera_period : 1;
    int64_t samples = period < 720 ? period : 720;
    double largest = 0.0;
    for (int64_t j = 0; j < samples; j++) {
        struct scene_camera cam;
        scene_camera_at(s, j * period / samples, &cam);
        for (int i = 0; i < s->instance_count; i++) {
            const struct scene_instance *in = &s->instances[i];
            if (in->mesh != SCENE_MESH_SPHERE)
                continue;
            float r = SCENE_SPHERE_RADIUS * in->scale;
            if (!scene_sphere_in_frustum(cam.view_proj, in->pos, r, false))
                continue;
            double px = scene_sphere_radius_px(&cam, spec->width, spec->height, in->pos, r);
            if (px > largest)
                largest = px;
        }
    }
    s->sphere_segments = spec->sphere_segments == SCENE_SEGMENTS_AUTO
                             ? scene_auto_segments(largest, spec->tessellation_error_px)
                             : spec->sphere_segments;
    s->sphere_radius_px = (float)largest;
    s->sphere_error_px = (float)(largest * scene_sphere_error(s->sphere_segments));
}
