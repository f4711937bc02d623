#ifndef SHADEBENCH_CUBE_FACES_H
#define SHADEBENCH_CUBE_FACES_H

/* The six faces of a cube map as GL numbers them (+x, -x, +y, -y, +z, -z):
 * each face's axes, and the view-projection that renders a face so that
 * its image is the face's texture (row 0 at t = -1), as the light probes
 * and the omni shadow maps render them. Kept in step with
 * shaders/common/cube_faces.glsl. GL-free; pure functions, any thread. */

#include <stdbool.h>

/* Direction of texel (s, t) in [-1, 1]^2 of face f: forward + s * s_axis +
 * t * t_axis (the GL specification's cube map table). */
void cube_face_axes(int face, float forward[3], float s_axis[3], float t_axis[3]);

/* Face of direction d (the major axis; ties as GL breaks them: x, then y). */
int cube_face_of(const float d[3]);

/* Column-major view-projection of face f seen from eye: a perspective with
 * a field of view of 90 degrees widened by the factor `widen` (>= 1: the
 * face's texels past tan = 1 hold a border for filtering), depth from near
 * to far. */
void cube_face_view_proj(int face, const float eye[3], float widen, float near_z, float far_z,
                         float out[16]);

/* Window depth in [0, 1] that cube_face_view_proj gives a point at
 * distance `major` along the face's forward axis. */
float cube_face_depth(float major, float near_z, float far_z);

#endif
