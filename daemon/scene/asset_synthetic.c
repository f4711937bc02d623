/* The textured preset's asset (asset_synthetic.h): geometry in world space
 * with tangents and both uv sets, images decoded to RGBA8, materials,
 * lights and cameras, exactly as the cache reader would hand them over. */
#include "daemon/scene/asset_synthetic.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const unsigned char ASSET_SYNTHETIC_FLAT_SRGB[3] = {200, 120, 60};

static const double PI = 3.14159265358979323846;
enum { GL_REPEAT_ = 10497, GL_CLAMP_ = 33071, GL_LINEAR_ = 9729,
       GL_LINEAR_MIPMAP_LINEAR_ = 9987 };

enum { IMG_CHECKER, IMG_NORMAL, IMG_MR, IMG_OCCLUSION, IMG_LEAVES, IMAGES };
enum { MAT_GROUND, MAT_PAINTED, MAT_METAL, MAT_EMISSIVE, MAT_SWATCH, MAT_LEAVES, MAT_GLASS,
       MATERIALS };

/* A mesh being built: vertices and indices appended, box kept. */
struct builder {
    struct asset_mesh *m;
    uint32_t vcap, icap;
};

static bool reserve(struct builder *b, uint32_t verts, uint32_t idx)
{
    struct asset_mesh *m = b->m;
    if (m->vertex_count + verts > b->vcap) {
        uint32_t cap = (m->vertex_count + verts) * 2;
        void *p = realloc(m->vertices, cap * sizeof(*m->vertices));
        if (!p)
            return false;
        m->vertices = p, b->vcap = cap;
    }
    if (m->index_count + idx > b->icap) {
        uint32_t cap = (m->index_count + idx) * 2;
        void *p = realloc(m->indices, cap * sizeof(*m->indices));
        if (!p)
            return false;
        m->indices = p, b->icap = cap;
    }
    return true;
}

/* A quad from corner o along edges eu (uv0 u, tangent) and ev (uv0 v),
 * facing eu x ev... given as n; uv0 over [u0, u1] x [v0, v1], uv1 the
 * chart c (u0, v0, u1, v1). */
static bool quad(struct builder *b, const float o[3], const float eu[3], const float ev[3],
                 const float n[3], const float uv0[4], const float chart[4])
{
    if (!reserve(b, 4, 6))
        return false;
    struct asset_mesh *m = b->m;
    uint32_t base = m->vertex_count;
    float lu = sqrtf(eu[0] * eu[0] + eu[1] * eu[1] + eu[2] * eu[2]);
    /* glTF's uv v runs down the image while ev runs up the surface:
     * bitangent = cross(n, t) * w points along -ev, so w is the sign that
     * makes it so. */
    float cross[3] = {n[1] * eu[2] - n[2] * eu[1], n[2] * eu[0] - n[0] * eu[2],
                      n[0] * eu[1] - n[1] * eu[0]};
    float w = cross[0] * ev[0] + cross[1] * ev[1] + cross[2] * ev[2] > 0 ? -1.0f : 1.0f;
    for (int c = 0; c < 4; c++) {
        float s = (float)(c & 1), t = (float)(c >> 1);
        struct asset_vertex *v = &m->vertices[base + (uint32_t)c];
        for (int k = 0; k < 3; k++) {
            v->pos[k] = o[k] + s * eu[k] + t * ev[k];
            v->normal[k] = n[k];
            v->tangent[k] = eu[k] / lu;
        }
        v->tangent[3] = w;
        v->uv0[0] = uv0[0] + s * (uv0[2] - uv0[0]);
        v->uv0[1] = uv0[3] + t * (uv0[1] - uv0[3]); /* up the surface is up the image */
        v->uv1[0] = chart[0] + s * (chart[2] - chart[0]);
        v->uv1[1] = chart[1] + t * (chart[3] - chart[1]);
        v->texcoord1[0] = v->uv1[0], v->texcoord1[1] = v->uv1[1];
        v->color[0] = v->color[1] = v->color[2] = v->color[3] = 1.0f;
    }
    /* Counter-clockwise seen from n. */
    bool ccw = (eu[1] * ev[2] - eu[2] * ev[1]) * n[0] + (eu[2] * ev[0] - eu[0] * ev[2]) * n[1] +
               (eu[0] * ev[1] - eu[1] * ev[0]) * n[2] > 0;
    static const uint32_t a[6] = {0, 1, 3, 0, 3, 2}, r[6] = {0, 3, 1, 0, 2, 3};
    for (int i = 0; i < 6; i++)
        m->indices[m->index_count + (uint32_t)i] = base + (ccw ? a[i] : r[i]);
    m->vertex_count += 4;
    m->index_count += 6;
    return true;
}

static bool box(struct builder *b, const float c[3], float h)
{
    /* Six faces, uv0 [0, 1] each, uv1 a 3 x 2 grid of charts with a gutter. */
    static const float faces[6][3][3] = {
        {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}},  {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
        {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}},  {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
        {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},   {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}},
    };
    for (int f = 0; f < 6; f++) {
        const float *n = faces[f][0], *u = faces[f][1], *v = faces[f][2];
        float o[3], eu[3], ev[3];
        for (int k = 0; k < 3; k++) {
            o[k] = c[k] + h * (n[k] - u[k] - v[k]);
            eu[k] = 2.0f * h * u[k];
            ev[k] = 2.0f * h * v[k];
        }
        float cu = (float)(f % 3) / 3.0f, cv = (float)(f / 3) / 2.0f;
        const float uv0[4] = {0, 0, 1, 1};
        const float chart[4] = {cu + 0.01f, cv + 0.01f, cu + 1.0f / 3.0f - 0.01f,
                                cv + 0.5f - 0.01f};
        if (!quad(b, o, eu, ev, n, uv0, chart))
            return false;
    }
    return true;
}

/* A lat-long sphere: uv0 = uv1 = (longitude, latitude) in [0, 1], tangent
 * along increasing longitude. */
static bool sphere(struct builder *b, const float c[3], float r, int seg)
{
    int rings = seg / 2;
    if (!reserve(b, (uint32_t)((seg + 1) * (rings + 1)), (uint32_t)(seg * rings * 6)))
        return false;
    struct asset_mesh *m = b->m;
    uint32_t base = m->vertex_count;
    for (int j = 0; j <= rings; j++)
        for (int i = 0; i <= seg; i++) {
            double u = (double)i / seg, v = (double)j / rings;
            double phi = 2.0 * PI * u, theta = PI * v;
            float n[3] = {(float)(sin(theta) * cos(phi)), (float)cos(theta),
                          (float)(-sin(theta) * sin(phi))};
            struct asset_vertex *vx = &m->vertices[m->vertex_count++];
            for (int k = 0; k < 3; k++) {
                vx->pos[k] = c[k] + r * n[k];
                vx->normal[k] = n[k];
            }
            vx->tangent[0] = (float)-sin(phi), vx->tangent[1] = 0.0f;
            vx->tangent[2] = (float)-cos(phi), vx->tangent[3] = 1.0f;
            vx->uv0[0] = vx->uv1[0] = vx->texcoord1[0] = (float)u;
            vx->uv0[1] = vx->uv1[1] = vx->texcoord1[1] = (float)v;
            vx->color[0] = vx->color[1] = vx->color[2] = vx->color[3] = 1.0f;
        }
    for (int j = 0; j < rings; j++)
        for (int i = 0; i < seg; i++) {
            uint32_t a = base + (uint32_t)(j * (seg + 1) + i), d = a + (uint32_t)(seg + 1);
            uint32_t t[6] = {a, d, a + 1, a + 1, d, d + 1};
            memcpy(&m->indices[m->index_count], t, sizeof(t));
            m->index_count += 6;
        }
    return true;
}

static void finish_mesh(struct asset_mesh *m, const char *name, int material)
{
    snprintf(m->name, sizeof(m->name), "%s", name);
    m->material = material;
    /* As a file with TEXCOORD_0 and a TEXCOORD_1 that is its uv1. */
    m->uv1_origin = ASSET_UV1_FILE;
    m->has_uv0 = m->has_texcoord1 = true;
    m->tangents_from_file = true;
    for (int k = 0; k < 3; k++) {
        m->box_min[k] = INFINITY;
        m->box_max[k] = -INFINITY;
    }
    for (uint32_t i = 0; i < m->vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            m->box_min[k] = fminf(m->box_min[k], m->vertices[i].pos[k]);
            m->box_max[k] = fmaxf(m->box_max[k], m->vertices[i].pos[k]);
        }
}

static uint8_t *image(struct asset *a, int i, const char *name, uint32_t edge)
{
    struct asset_image *im = &a->images[i];
    snprintf(im->name, sizeof(im->name), "%s", name);
    im->width = im->height = edge;
    im->rgba = calloc((size_t)edge * edge, 4);
    return im->rgba;
}

static void put(uint8_t *p, int r, int g, int b, int al)
{
    p[0] = (uint8_t)r, p[1] = (uint8_t)g, p[2] = (uint8_t)b, p[3] = (uint8_t)al;
}

static bool images(struct asset *a)
{
    enum { E = ASSET_SYNTHETIC_IMAGE_EDGE, F = ASSET_SYNTHETIC_FLAT_EDGE, S = 32 };
    uint8_t *chk = image(a, IMG_CHECKER, "checker", E), *nrm = image(a, IMG_NORMAL, "bumps", E),
            *mr = image(a, IMG_MR, "metal_rough", S), *occ = image(a, IMG_OCCLUSION, "grooves", S),
            *leaf = image(a, IMG_LEAVES, "leaves", E);
    if (!chk || !nrm || !mr || !occ || !leaf)
        return false;
    const unsigned char *f = ASSET_SYNTHETIC_FLAT_SRGB;
    for (int y = 0; y < E; y++)
        for (int x = 0; x < E; x++) {
            uint8_t *p = &chk[(y * E + x) * 4];
            if (x < F && y < F)
                put(p, f[0], f[1], f[2], 255);
            else if ((x / 8 + y / 8) % 2)
                put(p, 230, 230, 225, 255);
            else
                put(p, 60, 70, 90, 255);
            /* Bumps: a dome in every 16-texel cell, its slope as a tangent-
             * space normal (x along u, y along -v: up the image). */
            double cx = x % 16 - 7.5, cy = y % 16 - 7.5, d2 = cx * cx + cy * cy;
            double dx = 0, dy = 0;
            if (d2 < 49.0) {
                dx = -cx / 7.0 * 0.9;
                dy = cy / 7.0 * 0.9;
            }
            double len = sqrt(dx * dx + dy * dy + 1.0);
            put(&nrm[(y * E + x) * 4], (int)lround((dx / len * 0.5 + 0.5) * 255.0),
                (int)lround((dy / len * 0.5 + 0.5) * 255.0),
                (int)lround((1.0 / len * 0.5 + 0.5) * 255.0), 255);
            /* Leaves: a disc in every 16-texel cell, the colour everywhere so
             * that filtering never darkens the edge. */
            put(&leaf[(y * E + x) * 4], 70, 150, 55, d2 < 36.0 ? 255 : 0);
        }
    for (int y = 0; y < S; y++)
        for (int x = 0; x < S; x++) {
            /* Roughness (g) across, metallic (b) in the bottom quarter. */
            put(&mr[(y * S + x) * 4], 0, 50 + 180 * x / (S - 1), y >= 24 ? 255 : 0, 255);
            put(&occ[(y * S + x) * 4], x % 8 == 0 || y % 8 == 0 ? 120 : 255, 0, 0, 255);
        }
    return true;
}

static struct asset_texture_ref tex(int image, bool repeat)
{
    uint32_t wrap = repeat ? GL_REPEAT_ : GL_CLAMP_;
    return (struct asset_texture_ref){image, 0, wrap, wrap, GL_LINEAR_MIPMAP_LINEAR_,
                                      GL_LINEAR_, 1.0f, ASSET_UV_IDENTITY};
}

static void materials(struct asset *a)
{
    for (int i = 0; i < MATERIALS; i++) {
        struct asset_material *m = &a->materials[i];
        for (int k = 0; k < 4; k++)
            m->base_color[k] = 1.0f;
        m->metallic = 0.0f;
        m->roughness = 0.6f;
        m->alpha_mode = ASSET_ALPHA_OPAQUE;
        m->alpha_cutoff = 0.5f;
        for (int s = 0; s < ASSET_TEX_SLOTS; s++)
            m->tex[s] = (struct asset_texture_ref){-1, 0, GL_REPEAT_, GL_REPEAT_,
                                                   GL_LINEAR_MIPMAP_LINEAR_, GL_LINEAR_, 1.0f,
                                                   ASSET_UV_IDENTITY};
    }
    struct asset_material *m = &a->materials[MAT_GROUND];
    snprintf(m->name, sizeof(m->name), "ground");
    m->metallic = 1.0f, m->roughness = 1.0f; /* both from the texture */
    m->tex[ASSET_TEX_BASE_COLOR] = tex(IMG_CHECKER, true);
    m->tex[ASSET_TEX_NORMAL] = tex(IMG_NORMAL, true);
    m->tex[ASSET_TEX_METALLIC_ROUGHNESS] = tex(IMG_MR, true);
    m->tex[ASSET_TEX_OCCLUSION] = tex(IMG_OCCLUSION, true);
    m->tex[ASSET_TEX_OCCLUSION].scale = 0.8f;

    m = &a->materials[MAT_PAINTED];
    snprintf(m->name, sizeof(m->name), "painted");
    m->base_color[0] = 0.9f, m->base_color[1] = 0.8f, m->base_color[2] = 1.0f;
    m->roughness = 0.4f;
    m->tex[ASSET_TEX_BASE_COLOR] = tex(IMG_CHECKER, true);
    m->tex[ASSET_TEX_NORMAL] = tex(IMG_NORMAL, true);
    m->tex[ASSET_TEX_NORMAL].scale = 1.5f;
    /* The normal map read through uv set 1 (the same values as uv1 here). */
    m->tex[ASSET_TEX_NORMAL].uv_set = 1;

    m = &a->materials[MAT_METAL];
    snprintf(m->name, sizeof(m->name), "metal");
    m->base_color[0] = 1.0f, m->base_color[1] = 0.78f, m->base_color[2] = 0.35f;
    m->metallic = 1.0f, m->roughness = 1.0f;
    m->tex[ASSET_TEX_METALLIC_ROUGHNESS] = tex(IMG_MR, true);

    m = &a->materials[MAT_EMISSIVE];
    snprintf(m->name, sizeof(m->name), "emissive");
    m->base_color[0] = m->base_color[1] = m->base_color[2] = 0.1f;
    m->emissive[0] = 1.0f, m->emissive[1] = 0.6f, m->emissive[2] = 0.25f;
    /* The checker again, in the emissive (sRGB) role: one image, two uses. */
    m->tex[ASSET_TEX_EMISSIVE] = tex(IMG_CHECKER, true);

    m = &a->materials[MAT_SWATCH];
    snprintf(m->name, sizeof(m->name), "swatch");
    m->roughness = 1.0f;
    m->tex[ASSET_TEX_BASE_COLOR] = tex(IMG_CHECKER, false);

    m = &a->materials[MAT_LEAVES];
    snprintf(m->name, sizeof(m->name), "leaves");
    m->alpha_mode = ASSET_ALPHA_MASK;
    m->double_sided = true;
    m->tex[ASSET_TEX_BASE_COLOR] = tex(IMG_LEAVES, true);

    m = &a->materials[MAT_GLASS];
    snprintf(m->name, sizeof(m->name), "glass");
    m->alpha_mode = ASSET_ALPHA_BLEND;
    m->double_sided = true;
    m->base_color[0] = 0.6f, m->base_color[1] = 0.8f, m->base_color[2] = 1.0f;
    m->base_color[3] = 0.35f;
    m->roughness = 0.1f;
}

static void normalize3(float v[3])
{
    float l = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; k++)
        v[k] /= l;
}

static void lights_and_cameras(struct asset *a)
{
    struct asset_light *l = &a->lights[0];
    snprintf(l->name, sizeof(l->name), "spot");
    l->type = ASSET_LIGHT_SPOT;
    l->color[0] = 1.0f, l->color[1] = 0.95f, l->color[2] = 0.85f;
    l->intensity = 150.0f; /* candela */
    l->inner_cone = 0.35f, l->outer_cone = 0.6f;
    l->position[0] = 2.0f, l->position[1] = 7.0f, l->position[2] = 4.0f;
    l->direction[0] = -2.0f, l->direction[1] = -7.0f, l->direction[2] = -5.0f;
    normalize3(l->direction);
    l = &a->lights[1];
    snprintf(l->name, sizeof(l->name), "sun");
    l->type = ASSET_LIGHT_DIRECTIONAL;
    l->color[0] = 1.0f, l->color[1] = 0.98f, l->color[2] = 0.9f;
    l->intensity = 2.0f; /* lux: a white surface facing it shows 2 / pi at exposure 1 */
    l->direction[0] = 0.4f, l->direction[1] = -1.0f, l->direction[2] = -0.3f;
    normalize3(l->direction);

    static const struct {
        const char *name;
        float eye[3], target[3];
    } cams[2] = {{"main", {0.0f, 6.5f, 12.0f}, {0.0f, 1.0f, 0.0f}},
                 {"top", {0.0f, 16.0f, 6.0f}, {0.0f, 0.0f, 0.0f}}};
    for (int i = 0; i < 2; i++) {
        struct asset_camera *c = &a->cameras[i];
        snprintf(c->name, sizeof(c->name), "%s", cams[i].name);
        c->perspective = true;
        c->yfov = (float)(50.0 * PI / 180.0);
        c->znear = 0.1f;
        c->zfar = 100.0f;
        memcpy(c->eye, cams[i].eye, sizeof(c->eye));
        for (int k = 0; k < 3; k++)
            c->forward[k] = cams[i].target[k] - cams[i].eye[k];
        normalize3(c->forward);
        c->up[1] = 1.0f;
    }
}

static bool meshes(struct asset *a)
{
    struct builder b = {0};
    const float up[3] = {0, 1, 0}, toward[3] = {0, 0, 1};
    /* ground: 20 x 20, the checker tiled four times, uv1 the whole square. */
    b = (struct builder){&a->meshes[0], 0, 0};
    const float go[3] = {-10, 0, 10}, gu[3] = {20, 0, 0}, gv[3] = {0, 0, -20};
    const float guv[4] = {0, 0, 4, 4}, whole[4] = {0, 0, 1, 1};
    if (!quad(&b, go, gu, gv, up, guv, whole))
        return false;
    finish_mesh(b.m, "ground", MAT_GROUND);
    b = (struct builder){&a->meshes[1], 0, 0};
    if (!box(&b, (const float[3]){-3.5f, 1.0f, -1.0f}, 1.0f))
        return false;
    finish_mesh(b.m, "box", MAT_PAINTED);
    b = (struct builder){&a->meshes[2], 0, 0};
    if (!sphere(&b, (const float[3]){1.5f, 1.2f, -2.0f}, 1.2f, 32))
        return false;
    finish_mesh(b.m, "sphere", MAT_METAL);
    b = (struct builder){&a->meshes[3], 0, 0};
    if (!sphere(&b, (const float[3]){-1.0f, 0.5f, 2.5f}, 0.5f, 24))
        return false;
    finish_mesh(b.m, "lamp", MAT_EMISSIVE);
    /* swatch: 2.4 x 2.4 facing the camera, uv0 inside the checker's flat
     * quarter only, away from its edges by more than a filter's reach. */
    b = (struct builder){&a->meshes[4], 0, 0};
    const float so[3] = {-6.5f, 0.2f, 2.0f}, su[3] = {2.4f, 0, 0}, sv[3] = {0, 2.4f, 0};
    const float suv[4] = {0.06f, 0.06f, 0.44f, 0.44f};
    if (!quad(&b, so, su, sv, toward, suv, whole))
        return false;
    finish_mesh(b.m, "swatch", MAT_SWATCH);
    /* leaves: 3 x 3, the disc pattern twice across, seen from both sides. */
    b = (struct builder){&a->meshes[5], 0, 0};
    const float lo[3] = {3.0f, 0.1f, 1.5f}, lu[3] = {3.0f, 0, 0}, lv[3] = {0, 3.0f, 0};
    const float luv[4] = {0, 0, 2, 2};
    if (!quad(&b, lo, lu, lv, toward, luv, whole))
        return false;
    finish_mesh(b.m, "leaves", MAT_LEAVES);
    /* glass: a pane in front of the sphere and the lamp. */
    b = (struct builder){&a->meshes[6], 0, 0};
    const float po[3] = {-1.0f, 0.05f, 4.5f}, pu[3] = {3.0f, 0, 0}, pv[3] = {0, 2.4f, 0};
    if (!quad(&b, po, pu, pv, toward, whole, whole))
        return false;
    finish_mesh(b.m, "glass", MAT_GLASS);
    return true;
}

bool asset_synthetic_textured(struct asset *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof(*out));
    out->mesh_count = 7;
    out->material_count = MATERIALS;
    out->image_count = IMAGES;
    out->light_count = 2;
    out->camera_count = 2;
    out->meshes = calloc(out->mesh_count, sizeof(*out->meshes));
    out->materials = calloc(out->material_count, sizeof(*out->materials));
    out->images = calloc(out->image_count, sizeof(*out->images));
    out->lights = calloc(out->light_count, sizeof(*out->lights));
    out->cameras = calloc(out->camera_count, sizeof(*out->cameras));
    if (!out->meshes || !out->materials || !out->images || !out->lights || !out->cameras ||
        !images(out) || !meshes(out))
        goto fail;
    materials(out);
    lights_and_cameras(out);
    for (int k = 0; k < 3; k++) {
        out->box_min[k] = INFINITY;
        out->box_max[k] = -INFINITY;
        for (uint32_t m = 0; m < out->mesh_count; m++) {
            out->box_min[k] = fminf(out->box_min[k], out->meshes[m].box_min[k]);
            out->box_max[k] = fmaxf(out->box_max[k], out->meshes[m].box_max[k]);
        }
    }
    return true;
fail:
    asset_finish(out);
    snprintf(err, errlen, "out of memory building the textured preset's asset");
    return false;
}

