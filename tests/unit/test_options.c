/* Option tables (common/options.h) on their own: reading every kind of
 * option, dotted and nested names and the refusal of both, typo hints,
 * rules across fields, custom options, the JSON written back and the
 * /v1/info description, and the checks a table gets at registration. */
#include <stdlib.h>
#include <string.h>

#include "common/options.h"
#include "tests/unit/check.h"

struct opts {
    int tile;
    double radius;
    bool fallback;
    int normal, albedo;
    int size, atlas;
    int grid[3];
    int custom;
};

static const char *const normals[] = {"octahedral", "float3", NULL};
static const char *const albedos[] = {"rgba8", "packed", NULL};
static const int grid_default[3] = {4, 4, 8};

/* A custom option: "n" or ["n", "n", ...], kept as a count. */
static bool parse_count(const json_t *v, const char *field, void *opts, struct job_error *err)
{
    struct opts *o = opts;
    if (json_is_array(v)) {
        o->custom = (int)json_array_size(v);
        return true;
    }
    if (!json_is_string(v))
        return job_error_set(err, field, "must be a name or a list of names");
    o->custom = 1;
    return true;
}

static json_t *count_json(const void *opts)
{
    json_t *list = json_array();
    for (int i = 0; i < ((const struct opts *)opts)->custom; i++)
        json_array_append_new(list, json_string("n"));
    return list;
}

static void count_defaults(void *opts) { ((struct opts *)opts)->custom = 7; }

static const struct opt_hooks count_hooks = {
    .defaults = count_defaults, .parse = parse_count, .to_json = count_json, .type = "list",
    .rule = "must be a name or a list of names"};

static const struct opt_field fields[] = {
    {.name = "tile", .type = OPT_INT, .def = 16, .min = 8, .max = 128,
     .offset = offsetof(struct opts, tile)},
    {.name = "radius", .type = OPT_NUMBER, .def = 0.5, .min = 0, .max = 2,
     .offset = offsetof(struct opts, radius)},
    {.name = "fallback", .type = OPT_BOOL, .def = 1, .offset = offsetof(struct opts, fallback)},
    {.name = "gbuffer.normal", .type = OPT_CHOICE, .choices = normals,
     .offset = offsetof(struct opts, normal)},
    {.name = "gbuffer.albedo", .type = OPT_CHOICE, .choices = albedos, .def = 1,
     .offset = offsetof(struct opts, albedo)},
    {.name = "size", .type = OPT_POW2_OR_AUTO, .def = 0, .min = 8, .max = 1024,
     .auto_means = "sized on screen", .offset = offsetof(struct opts, size)},
    {.name = "deep.atlas.edge", .type = OPT_POW2, .def = 256, .min = 64, .max = 4096,
     .offset = offsetof(struct opts, atlas)},
    {.name = "grid", .type = OPT_INT_LIST, .count = 3, .def_list = grid_default, .min = 1,
     .max = 64, .offset = offsetof(struct opts, grid)},
    {.name = "names", .type = OPT_CUSTOM, .hooks = &count_hooks,
     .offset = offsetof(struct opts, custom)},
    {0},
};

static bool check(void *opts, const char *prefix, struct job_error *err)
{
    struct opts *o = opts;
    char field[64];
    snprintf(field, sizeof(field), "%s.tile", prefix);
    return o->tile <= o->atlas || job_error_set(err, field, "must be at most the atlas edge");
}

static const struct opt_table table = {.fields = fields, .size = sizeof(struct opts),
                                       .check = check};

static bool parse(const char *text, struct opts *o, struct job_error *err)
{
    json_t *v = json_loads(text, JSON_REJECT_DUPLICATES, NULL);
    CHECK(v != NULL);
    opt_defaults(&table, o);
    bool ok = v && opt_parse(&table, v, "demo", o, err);
    json_decref(v);
    return ok;
}

static void rejects(const char *text, const char *field, const char *message_part)
{
    struct opts o;
    struct job_error err = {{0}, {0}};
    bool ok = parse(text, &o, &err);
    CHECK(!ok && strcmp(err.field, field) == 0);
    CHECK(!message_part || strstr(err.message, message_part));
    if (ok || strcmp(err.field, field) != 0 || (message_part && !strstr(err.message, message_part)))
        fprintf(stderr, "  for %s: got %s: %s\n", text, ok ? "(accepted)" : err.field,
                err.message);
}

static void test_reading(void)
{
    struct opts o, again;
    struct job_error err;
    CHECK(parse("{}", &o, &err));
    CHECK(o.tile == 16 && o.radius == 0.5 && o.fallback && o.normal == 0 && o.albedo == 1 &&
          o.size == 0 && o.atlas == 256 && o.grid[2] == 8 && o.custom == 7);

    CHECK(parse("{\"tile\": 32.0, \"radius\": 1.5, \"fallback\": false, \"size\": 64,"
                " \"grid\": [1, 2, 3], \"names\": [\"a\", \"b\"],"
                " \"gbuffer\": {\"normal\": \"float3\"}, \"deep\": {\"atlas\": {\"edge\": 1024}}}",
                &o, &err));
    CHECK(o.tile == 32 && o.radius == 1.5 && !o.fallback && o.size == 64 && o.grid[1] == 2 &&
          o.custom == 2 && o.normal == 1 && o.albedo == 1 && o.atlas == 1024);

    /* Dotted names read as the nested form does, at any depth and mixed. */
    CHECK(parse("{\"tile\": 32.0, \"radius\": 1.5, \"fallback\": false, \"size\": 64,"
                " \"grid\": [1, 2, 3], \"names\": [\"a\", \"b\"],"
                " \"gbuffer.normal\": \"float3\", \"deep.atlas\": {\"edge\": 1024}}",
                &again, &err));
    CHECK(memcmp(&o, &again, sizeof(o)) == 0);
    CHECK(parse("{\"deep.atlas.edge\": 1024, \"gbuffer\": {\"albedo\": \"rgba8\"}}", &o, &err) &&
          o.atlas == 1024 && o.albedo == 0);
    CHECK(parse("{\"deep\": {\"atlas.edge\": 512}}", &o, &err) && o.atlas == 512);

    /* The JSON written back nests, and reads back the same. */
    CHECK(parse("{\"gbuffer.normal\": \"float3\", \"size\": 128}", &o, &err));
    json_t *j = opt_to_json(&table, &o);
    CHECK(strcmp(json_string_value(json_object_get(json_object_get(j, "gbuffer"), "normal")),
                 "float3") == 0);
    CHECK(json_integer_value(json_object_get(json_object_get(json_object_get(j, "deep"),
                                                             "atlas"), "edge")) == 256);
    CHECK(json_array_size(json_object_get(j, "names")) == 7);
    opt_defaults(&table, &again);
    CHECK(opt_parse(&table, j, "demo", &again, &err) && again.normal == 1 && again.size == 128);
    json_decref(j);
    opt_defaults(&table, &again);
    j = opt_to_json(&table, &again);
    CHECK(strcmp(json_string_value(json_object_get(j, "size")), "auto") == 0);
    json_decref(j);
}

static void test_refusals(void)
{
    rejects("[]", "demo", "must be an object");
    rejects("{\"tile\": 4}", "demo.tile", "must be an integer from 8 to 128");
    rejects("{\"tile\": 16.5}", "demo.tile", NULL);
    rejects("{\"radius\": \"far\"}", "demo.radius", "must be a number from 0 to 2");
    rejects("{\"fallback\": 1}", "demo.fallback", "must be true or false");
    rejects("{\"gbuffer\": {\"normal\": \"packed\"}}", "demo.gbuffer.normal",
            "must be one of: \"octahedral\", \"float3\"");
    rejects("{\"gbuffer.normal\": \"packed\"}", "demo.gbuffer.normal", NULL);
    rejects("{\"size\": 48}", "demo.size",
            "must be \"auto\" (sized on screen) or a power of two from 8 to 1024");
    rejects("{\"deep.atlas.edge\": 100}", "demo.deep.atlas.edge",
            "must be a power of two from 64 to 4096");
    rejects("{\"grid\": [1, 2]}", "demo.grid", "a list of 3 integers");
    rejects("{\"names\": 3}", "demo.names", "a name or a list");
    rejects("{\"gbuffer\": 3}", "demo.gbuffer", "must be an object");
    rejects("{\"deep\": {\"atlas\": []}}", "demo.deep.atlas", "must be an object");
    /* Typos get the closest name, dotted or nested. */
    rejects("{\"gbuffer\": {\"normals\": \"float3\"}}", "demo.gbuffer.normals",
            "did you mean 'demo.gbuffer.normal'");
    rejects("{\"gbuffer.normals\": \"float3\"}", "demo.gbuffer.normals",
            "did you mean 'demo.gbuffer.normal'");
    rejects("{\"tiel\": 16}", "demo.tiel", "did you mean 'demo.tile'");
    /* Both forms of one option: refused, naming it and the two spellings. */
    rejects("{\"gbuffer\": {\"normal\": \"float3\"}, \"gbuffer.normal\": \"float3\"}",
            "demo.gbuffer.normal", "given twice");
    rejects("{\"deep\": {\"atlas\": {\"edge\": 64}, \"atlas.edge\": 64}}", "demo.deep.atlas.edge",
            "as \"deep\": {\"atlas\": {\"edge\"}} and as \"deep\": {\"atlas.edge\"}");
    /* Rules across fields run after every field, naming the field. */
    rejects("{\"tile\": 128, \"deep.atlas.edge\": 64}", "demo.tile", "at most the atlas");
}

static void test_description(void)
{
    json_t *d = opt_describe(&table);
    json_t *size = json_object_get(d, "size"), *normal = json_object_get(d, "gbuffer.normal");
    CHECK(strcmp(json_string_value(json_object_get(size, "type")), "power_of_two_or_auto") == 0);
    CHECK(strcmp(json_string_value(json_object_get(size, "default")), "auto") == 0);
    CHECK(json_number_value(json_object_get(size, "max")) == 1024);
    CHECK(json_array_size(json_object_get(normal, "choices")) == 2);
    CHECK(strcmp(json_string_value(json_object_get(json_object_get(d, "deep.atlas.edge"),
                                                   "type")), "power_of_two") == 0);
    json_t *names = json_object_get(d, "names");
    CHECK(strcmp(json_string_value(json_object_get(names, "type")), "list") == 0 &&
          json_is_false(json_object_get(names, "sweepable")) &&
          json_array_size(json_object_get(names, "default")) == 7);
    CHECK(json_is_true(json_object_get(json_object_get(d, "tile"), "sweepable")));
    json_decref(d);
    static const char *const passes[] = {"one", "two", NULL};
    json_t *part = opt_part_json("demo", "a demo", passes, &table);
    CHECK(json_array_size(json_object_get(part, "passes")) == 2 &&
          json_object_size(json_object_get(part, "options")) == 9);
    json_decref(part);
    CHECK(opt_find(&table, "gbuffer.albedo") == &fields[4] && !opt_find(&table, "gbuffer"));
}

static void test_registration(void)
{
    char err[256];
    CHECK(opt_table_check(&table, "demo", err, sizeof(err)));
    struct opt_table none = {0};
    CHECK(opt_table_check(&none, "none", err, sizeof(err)));
    /* Each of these tables is refused, naming the option. */
    static const struct opt_field twice[] = {
        {.name = "a", .type = OPT_BOOL, .offset = 0}, {.name = "a", .type = OPT_BOOL, .offset = 1},
        {0}};
    static const struct opt_field group[] = {
        {.name = "a", .type = OPT_BOOL, .offset = 0}, {.name = "a.b", .type = OPT_BOOL, .offset = 1},
        {0}};
    static const struct opt_field outside[] = {
        {.name = "a", .type = OPT_NUMBER, .def = 0, .max = 1, .offset = 4}, {0}};
    static const struct opt_field bad_default[] = {
        {.name = "a", .type = OPT_INT, .def = 9, .min = 0, .max = 4, .offset = 0}, {0}};
    static const struct opt_field no_choices[] = {{.name = "a", .type = OPT_CHOICE, .offset = 0},
                                                  {0}};
    static const struct opt_field bad_name[] = {{.name = "a..b", .type = OPT_BOOL, .offset = 0},
                                                {0}};
    const struct opt_field *const bad[] = {twice, group, outside, bad_default, no_choices,
                                           bad_name};
    for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
        struct opt_table t = {.fields = bad[i], .size = 8};
        err[0] = '\0';
        CHECK(!opt_table_check(&t, "bad", err, sizeof(err)) && strstr(err, "bad: ") == err);
    }
}

int main(void)
{
    test_reading();
    test_refusals();
    test_description();
    test_registration();
    return check_finish("test_options");
}
