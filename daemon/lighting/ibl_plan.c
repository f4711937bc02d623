#include "daemon/lighting/ibl_plan.h"

#include <math.h>

void ibl_place_probes(const struct scene *s, const struct ibl_spec *spec, struct ibl_probe *out)
{
    if (spec->placed) {
        for (int i = 0; i < spec->probes; i++) {
            for (int k = 0; k < 3; k++)
                out[i].pos[k] = (float)spec->probe[i].pos[k];
            out[i].radius = (float)spec->probe[i].radius;
        }
        return;
    }
    const struct scene_box *b = &s->objects;
    int n = spec->probes;
    if (n <= 0)
        return;
    int cols = (int)ceil(sqrt((double)n)), rows = (n + cols - 1) / cols;
    float size[3] = {b->max[0] - b->min[0], b->max[1] - b->min[1], b->max[2] - b->min[2]};
    float diag = sqrtf(size[0] * size[0] + size[1] * size[1] + size[2] * size[2]);
    float cell_x = size[0] / cols, cell_z = size[2] / rows;
    for (int i = 0; i < n; i++) {
        int r = i / cols, c = i % cols;
        /* The last row's probes spread over its width. */
        int in_row = r == rows - 1 ? n - r * cols : cols;
        float cx = size[0] / in_row;
        out[i].pos[0] = b->min[0] + (c + 0.5f) * (r == rows - 1 ? cx : cell_x);
        out[i].pos[1] = b->max[1] + 0.1f * diag;
        out[i].pos[2] = b->min[2] + (r + 0.5f) * cell_z;
        float half = 0.5f * sqrtf(cx * cx + cell_z * cell_z + size[1] * size[1]);
        out[i].radius = 2.0f * fmaxf(half, 0.05f * diag);
    }
}

int ibl_select(const struct ibl_probe *probes, int n, const float eye[3], int blend, int *out)
{
    int count = 0;
    float imp[IBL_MAX_BLEND];
    for (int i = 0; i < n; i++) {
        float d[3] = {probes[i].pos[0] - eye[0], probes[i].pos[1] - eye[1],
                      probes[i].pos[2] - eye[2]};
        float dist = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        float v = probes[i].radius / fmaxf(dist, 1e-3f);
        /* Insert into the sorted top list; later equal values stay after. */
        int at = count;
        while (at > 0 && imp[at - 1] < v)
            at--;
        if (at >= blend)
            continue;
        for (int k = (count < blend ? count : blend - 1); k > at; k--) {
            imp[k] = imp[k - 1];
            out[k] = out[k - 1];
        }
        imp[at] = v;
        out[at] = i;
        if (count < blend)
            count++;
    }
    return count;
}

float ibl_probe_weight(const struct ibl_probe *probe, const float p[3])
{
    float d[3] = {p[0] - probe->pos[0], p[1] - probe->pos[1], p[2] - probe->pos[2]};
    float t = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / probe->radius;
    float w = fmaxf(0.0f, 1.0f - t);
    return w * w * (3.0f - 2.0f * w);
}
