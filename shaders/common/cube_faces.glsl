// The cube map faces as GL numbers them (+x, -x, +y, -y, +z, -z), in step
// with daemon/lighting/cube_faces.c: direction = forward + s s_axis + t t_axis.
void cube_face_axes(int f, out vec3 fw, out vec3 sa, out vec3 ta)
{
    if (f == 0) {
        fw = vec3(1, 0, 0), sa = vec3(0, 0, -1), ta = vec3(0, -1, 0);
    } else if (f == 1) {
        fw = vec3(-1, 0, 0), sa = vec3(0, 0, 1), ta = vec3(0, -1, 0);
    } else if (f == 2) {
        fw = vec3(0, 1, 0), sa = vec3(1, 0, 0), ta = vec3(0, 0, 1);
    } else if (f == 3) {
        fw = vec3(0, -1, 0), sa = vec3(1, 0, 0), ta = vec3(0, 0, -1);
    } else if (f == 4) {
        fw = vec3(0, 0, 1), sa = vec3(1, 0, 0), ta = vec3(0, -1, 0);
    } else {
        fw = vec3(0, 0, -1), sa = vec3(-1, 0, 0), ta = vec3(0, -1, 0);
    }
}

int cube_face_of(vec3 d)
{
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z)
        return d.x >= 0.0 ? 0 : 1;
    if (a.y >= a.z)
        return d.y >= 0.0 ? 2 : 3;
    return d.z >= 0.0 ? 4 : 5;
}

// Window depth of a point `major` along a face's forward axis.
float cube_face_depth(float major, float n, float f)
{
    float A = (f + n) / (n - f), B = 2.0 * f * n / (n - f);
    return 0.5 * ((A * -major + B) / major) + 0.5;
}
