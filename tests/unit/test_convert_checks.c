/* The converter's checks (daemon/assets/convert_checks.c) in time linear in
 * the nodes (issue 34): a million root nodes, most of a million nodes in
 * chains 256 deep, and a mesh drawn by 60,000 nodes, each checked under a
 * CPU-time limit (RLIMIT_CPU, scaled by SHADEBENCH_TIME_SCALE) that the
 * old checks, quadratic in nodes times roots, ran minutes past: a run over
 * it dies of SIGXCPU and fails. And the graph's rules at their edges: 256
 * levels pass, 257 are refused naming the deepest node, a cycle is
 * refused, and a node outside the scene adds no mesh instance. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "daemon/assets/asset_convert.h"
#include "tests/unit/check.h"

/* A growing string. */
struct text {
    char *s;
    size_t len, cap;
};

static void put(struct text *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void put(struct text *t, const char *fmt, ...)
{
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(t->s + t->len, t->cap - t->len, fmt, ap);
        va_end(ap);
        if (n >= 0 && (size_t)n < t->cap - t->len) {
            t->len += (size_t)n;
            return;
        }
        t->cap = t->cap * 2 + (size_t)n + 64;
        t->s = realloc(t->s, t->cap);
        if (!t->s)
            abort();
    }
}

/* One triangle as a data URI buffer: 9 floats, 36 bytes. */
static const char TRIANGLE[] =
    "\"buffers\":[{\"byteLength\":36,\"uri\":\"data:application/octet-stream;base64,"
    "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}],"
    "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
    "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],";

/* nodes nodes; node i's parent is parent(i) (-1: a root, listed in the
 * scene when listed(i)); mesh_node(i): it draws mesh 0. */
static struct text document(size_t nodes, long (*parent)(size_t), bool (*listed)(size_t),
                            bool (*mesh_node)(size_t))
{
    struct text t = {0};
    put(&t, "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,%s\"nodes\":[", TRIANGLE);
    /* children lists: node i's children are the nodes whose parent is i;
     * the shapes here make each node's children a run of later indices. */
    size_t *first = calloc(nodes + 1, sizeof(size_t)), *count = calloc(nodes + 1, sizeof(size_t));
    for (size_t i = 0; i < nodes; i++) {
        long p = parent(i);
        if (p >= 0) {
            if (!count[p])
                first[p] = i;
            count[p]++;
        }
    }
    for (size_t i = 0; i < nodes; i++) {
        put(&t, "%s{", i ? "," : "");
        bool comma = false;
        if (mesh_node(i)) {
            put(&t, "\"mesh\":0");
            comma = true;
        }
        if (count[i]) {
            put(&t, "%s\"children\":[", comma ? "," : "");
            for (size_t k = 0; k < count[i]; k++)
                put(&t, "%s%zu", k ? "," : "", first[i] + k);
            put(&t, "]");
        }
        put(&t, "}");
    }
    put(&t, "],\"scenes\":[{\"nodes\":[");
    bool any = false;
    for (size_t i = 0; i < nodes; i++)
        if (parent(i) < 0 && listed(i)) {
            put(&t, "%s%zu", any ? "," : "", i);
            any = true;
        }
    put(&t, "]}]}");
    free(first);
    free(count);
    return t;
}

static bool check_doc(const struct text *t, uint32_t max_nodes, struct asset *a,
                      struct asset_convert_error *err)
{
    struct asset_limits lim;
    asset_limits_defaults(&lim);
    lim.max_nodes = max_nodes;
    lim.max_meshes = 1u << 20;
    return asset_convert_checks((const uint8_t *)t->s, t->len, &lim, a, err);
}

static long root(size_t i) { (void)i; return -1; }
static bool always(size_t i) { (void)i; return true; }
static bool first_only(size_t i) { return i == 0; }
static bool below_60k(size_t i) { return i < 60000; }
/* Chains of 256 levels: node i's parent is i - 1 except at each chain's top. */
static long chain256(size_t i) { return i % 256 ? (long)i - 1 : -1; }
static bool chain_bottom(size_t i) { return i % 256 == 255; }
static size_t chain_levels;
static long chain(size_t i) { return i ? (long)i - 1 : -1; }
static bool bottom(size_t i) { return i == chain_levels - 1; }
static bool even(size_t i) { return i % 2 == 0; }
static bool not_listed_half(size_t i) { return i < 2; }

int main(void)
{
    const char *scale_env = getenv("SHADEBENCH_TIME_SCALE");
    double scale = scale_env && atof(scale_env) > 0 ? atof(scale_env)
                   : getenv("SHADEBENCH_SANITIZERS")   ? 10
                                                       : 1;
    /* The old checks took 9 s of CPU for 20,000 roots and were still at it
     * after 180 s for a million; these take well under a second each. */
    struct rlimit cpu = {(rlim_t)(60 * scale), (rlim_t)(60 * scale) + 5};
    setrlimit(RLIMIT_CPU, &cpu);

    struct asset a;
    struct asset_convert_error err;

    /* A million root nodes, one drawing the triangle. */
    struct text t = document(1000000, root, always, first_only);
    bool ok = check_doc(&t, 1u << 21, &a, &err);
    CHECK(ok);
    if (!ok)
        fprintf(stderr, "a million roots: %d %s %s\n", err.status, err.field, err.message);
    asset_finish(&a);
    /* And under the default limit: refused by their count, naming it. */
    ok = check_doc(&t, 1u << 18, &a, &err);
    CHECK(!ok && err.status == 422 && strcmp(err.field, "limits.max_nodes") == 0);
    asset_finish(&a);
    free(t.s);

    /* 60,000 mesh nodes among 60,000 roots (the old checks: 146 s). */
    t = document(60000, root, always, below_60k);
    ok = check_doc(&t, 1u << 18, &a, &err);
    CHECK(ok);
    asset_finish(&a);
    free(t.s);

    /* 1,024 chains of 256 levels, the bottom of each drawing the mesh. */
    t = document(256 * 1024, chain256, always, chain_bottom);
    ok = check_doc(&t, 1u << 18, &a, &err);
    CHECK(ok);
    if (!ok)
        fprintf(stderr, "chains: %d %s %s\n", err.status, err.field, err.message);
    asset_finish(&a);
    free(t.s);

    /* 256 levels pass; 257 are refused, naming the node at level 257. */
    chain_levels = 256;
    t = document(chain_levels, chain, always, bottom);
    CHECK(check_doc(&t, 1u << 18, &a, &err));
    asset_finish(&a);
    free(t.s);
    chain_levels = 257;
    t = document(chain_levels, chain, always, bottom);
    ok = check_doc(&t, 1u << 18, &a, &err);
    CHECK(!ok && err.status == 422 && strcmp(err.field, "nodes[256]") == 0);
    asset_finish(&a);
    free(t.s);

    /* A cycle (0 -> 1 -> 0) is refused: it has no root. */
    const char *cycle = "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{\"children\":[1]},"
                        "{\"children\":[0]}],\"scenes\":[{\"nodes\":[]}]}";
    struct asset_limits lim;
    asset_limits_defaults(&lim);
    ok = asset_convert_checks((const uint8_t *)cycle, strlen(cycle), &lim, &a, &err);
    CHECK(!ok && err.status == 422 && strncmp(err.field, "nodes[", 6) == 0);
    asset_finish(&a);

    /* Roots the scene does not list add no instance: 4 roots, 2 listed,
     * every even node drawing the mesh, so one instance of the two listed
     * counts; with max_meshes 1 that passes, as it would not with both. */
    t = document(4, root, not_listed_half, even);
    asset_limits_defaults(&lim);
    lim.max_meshes = 1;
    ok = asset_convert_checks((const uint8_t *)t.s, t.len, &lim, &a, &err);
    CHECK(ok);
    asset_finish(&a);
    free(t.s);
    return check_finish("test_convert_checks");
}
