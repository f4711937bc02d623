/* The HTTP routing on any method and path. Invariants: it never crashes;
 * every path maps to one kind; a resource's id holds only digits and
 * dashes, its frame is positive, its chart name has no path characters;
 * every refusal names a field and a message; every kind has a label and an
 * Allow header; the raw target's checks refuse any '%' without two hex
 * digits (issue 34). */
#include <ctype.h>
#include <string.h>

#include "daemon/api/routes.h"
#include "tests/fuzz/fuzz.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const char *const METHODS[] = {"GET", "HEAD", "POST", "DELETE", "PUT", "OPTIONS",
                                          "PATCH", ""};
    if (size == 0 || size > 4096)
        return 0;
    const char *method = METHODS[data[0] % 8];
    char url[4097];
    memcpy(url, data + 1, size - 1);
    url[size - 1] = '\0';
    /* The raw target's checks (on_uri): a refusal names a field and a
     * rule, and a '%' without two hexadecimal digits is always refused. */
    size_t args;
    const char *field = NULL, *target_rule = NULL;
    bool target_ok = route_check_target(url, &args, &field, &target_rule);
    FUZZ_ASSERT(target_ok || (field && field[0] && target_rule && target_rule[0]));
    for (const char *p = strchr(url, '%'); p; p = strchr(p + 1, '%')) {
        bool hex = isxdigit((unsigned char)p[1]) && isxdigit((unsigned char)p[2]);
        FUZZ_ASSERT(hex || !target_ok);
    }
    struct route r;
    bool found = route_parse(url, &r);
    FUZZ_ASSERT(found == (r.kind != ROUTE_NONE));
    FUZZ_ASSERT((unsigned)r.kind < ROUTE_COUNT);
    if (!found) {
        FUZZ_ASSERT(r.field && r.field[0] && r.message && r.message[0]);
    } else {
        for (const char *p = r.id; *p; p++)
            FUZZ_ASSERT((*p >= '0' && *p <= '9') || *p == '-');
        bool has_id = r.kind != ROUTE_HEALTHZ && r.kind != ROUTE_METRICS && r.kind != ROUTE_INFO &&
                      r.kind != ROUTE_JOBS && r.kind != ROUTE_SWEEPS && r.kind != ROUTE_ASSETS &&
                      r.kind != ROUTE_ASSET;
        /* An asset's name is what the request named, for the handler to
         * judge (scene_asset_name_valid); it is never empty and never holds
         * a path separator. */
        if (r.kind == ROUTE_ASSET)
            FUZZ_ASSERT(r.asset[0] != '\0' && strchr(r.asset, '/') == NULL);
        FUZZ_ASSERT(has_id == (r.id[0] != '\0'));
        if (r.kind == ROUTE_JOB_IMAGE)
            FUZZ_ASSERT(r.frame >= 1 && r.frame <= 999999999);
        if (r.kind == ROUTE_JOB_CHART || r.kind == ROUTE_SWEEP_CHART) {
            FUZZ_ASSERT(r.chart[0] != '\0');
            FUZZ_ASSERT(strpbrk(r.chart, "/.%\\\\") == NULL);
        }
        /* What a path names does not depend on trailing bytes after a NUL. */
        FUZZ_ASSERT(strlen(url) < sizeof(url));
    }
    FUZZ_ASSERT((route_label(r.kind) != NULL && route_label(r.kind)[0] == '/') ||
                strcmp(route_label(r.kind), "other") == 0);
    const char *allow, *rule;
    bool ok = route_method_ok(r.kind, method, &allow, &rule);
    FUZZ_ASSERT(allow && allow[0] && rule && rule[0]);
    if (strcmp(method, "GET") == 0 || strcmp(method, "HEAD") == 0)
        FUZZ_ASSERT(ok);
    /* PUT uploads an asset, and nothing else. */
    if (strcmp(method, "PUT") == 0)
        FUZZ_ASSERT(ok == (r.kind == ROUTE_ASSET));
    if (strcmp(method, "PATCH") == 0 || method[0] == '\0')
        FUZZ_ASSERT(!ok);
    return 0;
}
