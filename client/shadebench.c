/* shadebench: the client for CI farms and people. Submits jobs to
 * shadebenchd, follows them, downloads everything, and turns quality and
 * timing into a verdict: JUnit XML for CI systems and an exit status (0
 * pass, 1 regression or quality failure, 2 usage, server or mismatch
 * error). This file reads the command line; the commands live in
 * cmd_*.c, the statistics in gate.c and stats_test.c. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "client/client.h"
#include "client/suggest.h"
#include "common/fsutil.h"
#include "config.h"
#include "common/noise.h"
#include "common/result_keys.h"

static void die_usage(const char *fmt, ...) __attribute__((format(printf, 1, 2), noreturn));
static void die_usage(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("shadebench: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    exit(EXIT_ERROR);
}

static void usage(FILE *f)
{
    fprintf(f,
            "Usage: shadebench [OPTION]... COMMAND [ARG]...\n"
            "Drives shadebenchd from CI farms and terminals.\n\n"
            "Commands:\n"
            "  submit JOB.json     submit a job (prints its id); with --wait follow it to the end;\n"
            "                      with --baseline, the timing gate over several runs\n"
            "  ab A.json B.json    run A and B alternately, report B/A with its interval\n"
            "  ab JOB.json --server-b URL   the same job on two daemons\n"
            "  sweep SWEEP.json    start a sweep; with --wait --out DIR download its table,\n"
            "                      charts and report\n"
            "  sweep SWEEP.json --slurm --out DIR   run the sweep's points as Slurm job arrays\n"
            "                      (shadebenchd --once on the nodes), then gather them\n"
            "  sweep --slurm --resume DIR           gather what finished, run what is missing\n"
            "  plan SWEEP.json --out DIR   only expand the sweep into DIR/plan/N.json, for CI\n"
            "                      runners that run each point with shadebenchd --once\n"
            "  gather DIR...       merge fleet folders (Slurm's, or CI runners' tasks/LABEL/N)\n"
            "                      into one sweep result (--out OUT, default the first DIR)\n"
            "  compare-devices DIR the device table of a gathered sweep\n"
            "  history             finished jobs matching --filter, with a trend (--out DIR)\n"
            "  status ID           one line: status, technique, progress, error\n"
            "  list                every job, one a line\n"
            "  cancel ID           cancel a queued or running job\n"
            "  fetch ID            download a finished job (--out DIR) and judge it\n"
            "  info                the daemon's version, device, techniques, effects and limits\n"
            "                      (--json: the daemon's whole answer)\n"
            "  fidelity ASSET [REQUEST.json]  the asset against the Khronos glTF Sample Viewer,\n"
            "                      lit and per channel (--channel NAME, repeatable; --out DIR:\n"
            "                      both renders and the difference images; --min-ssim,\n"
            "                      --max-flip fail a channel)\n\n"
            "Options:\n"
            "  --server URL        default $SHADEBENCH_SERVER, else http://127.0.0.1:8460\n"
            "  --token-file FILE   bearer token from a file (default $SHADEBENCH_TOKEN_FILE)\n"
            "  --token TOKEN       bearer token on the command line (visible to other users;\n"
            "                      prefer --token-file or $SHADEBENCH_TOKEN)\n"
            "  --wait              follow the job with progress until it ends\n"
            "  --out DIR           download job.json, result.json, timings.csv and images into\n"
            "                      DIR, which must be empty or new (or hold this same job)\n"
            "  --junit FILE        write JUnit XML\n"
            "  --label KEY=VALUE   add a label to the submitted jobs (repeatable)\n"
            "  --min-ssim X        a capture fails below this SSIM (the job must name a\n"
            "                      reference and capture frames: checked before it runs)\n"
            "  --max-flip X        a capture fails above this mean FLIP (likewise)\n\n"
            "Timing gate (submit --wait --baseline) and ab:\n"
            "  --baseline FILE     result.json (or job.json) of earlier runs to compare with\n"
            "  --runs N            clean runs kept on each side (default: the job's repeat, else 5)\n"
            "  --max-slowdown P%%   the smallest slowdown that counts (default 5%%); percentages\n"
            "                      take their sign: 5 alone is refused\n"
            "  --max-reruns N      at most N extra runs (ab: pairs) for noisy runs, unclear\n"
            "                      verdicts and confirming a regression (default 10)\n"
            "  --fail-inconclusive exit 3 when still too noisy to tell (default: exit 0 with a\n"
            "                      warning; either way JUnit marks it skipped, not passed);\n"
            "                      $SHADEBENCH_FAIL_INCONCLUSIVE=1 sets it for CI\n"
            "  --no-fail-inconclusive  the default, over $SHADEBENCH_FAIL_INCONCLUSIVE\n"
            "  --allow-mismatch    compare with a baseline of another job or device\n"
            "  --series NAME       frame_ms, gpu_ms or cpu_ms (default: frame_ms on software\n"
            "                      renderers such as llvmpipe, gpu_ms on GPUs)\n"
            "  --confidence P%%     of the intervals (default 95%%)\n"
            "  --noise-tolerance P%% a run left by other processes more than P%% more or less CPU\n"
            "                      than the runs it is compared with is noisy and rerun\n"
            "                      (default 10%%; off: never)\n"
            "  --server-b URL      ab: the second daemon\n\n"
            "History:\n"
            "  --filter KEY=VALUE  technique=, status=, label.NAME= (repeatable); limit=N: pages\n"
            "                      of N jobs (default: the daemon's, 100), read to the end\n"
            "  --since TIME        jobs created since TIME (2026-11-21, 2026-11-21T10:00:00Z, or\n"
            "                      seconds since 1970)\n"
            "  --figure NAME       frame_ms, gpu_ms, cpu_ms or worst_ssim (default as --series)\n\n"
            "Fleet (sweep --slurm; see docs/fleet.md):\n"
            "  --slurm             submit the points to Slurm instead of a daemon\n"
            "  --devices D1,D2     one array per device class, each constrained to the node\n"
            "                      feature of its name (or NAME=CONSTRAINT)\n"
            "  --constraint C      one device class, the nodes with feature C\n"
            "  --partition P       sbatch --partition\n"
            "  --gres G            sbatch --gres, e.g. gpu:1\n"
            "  --max-parallel N    at most N tasks of an array at once (--array=...%%N)\n"
            "  --time-limit T      sbatch --time for each task\n"
            "  --requeue           let Slurm requeue a task whose node fails\n"
            "  --shadebenchd PATH  the daemon on the nodes (default: the one beside this client)\n"
            "  --resume DIR        complete a fleet folder: resubmit only the missing points\n\n"
            "  --timeout S         give up waiting after S seconds\n"
            "  --quiet             no progress or verdict lines on stderr\n\n"
            "On a terminal the verdicts are in colour (not with NO_COLOR set) and a bar shows\n"
            "each job's progress; a pipe gets plain lines, stdout line-buffered.\n\n"
            "Exit status: 0 pass, 1 regression or quality failure (or a failed job),\n"
            "2 usage, server or baseline-mismatch error, 3 a timing verdict too noisy to\n"
            "reach with --fail-inconclusive (and nothing failed).\n");
}

/* A token file: its first line, whitespace trimmed. */
static char *read_token_file(const char *path, const char *source)
{
    size_t len;
    char *text = fs_read_file(path, 64 * 1024, &len);
    if (!text)
        die_usage("cannot read the token file %s (%s): %s", path, source, strerror(errno));
    text[strcspn(text, "\r\n")] = '\0';
    size_t n = strlen(text);
    while (n && (text[n - 1] == ' ' || text[n - 1] == '\t'))
        text[--n] = '\0';
    if (!n)
        die_usage("the token file %s is empty", path);
    return text;
}

static void key_value(const char *arg, const char *flag, json_t *into)
{
    const char *eq = strchr(arg, '=');
    if (!eq || eq == arg)
        die_usage("%s takes KEY=VALUE, got \"%s\"", flag, arg);
    char key[128];
    snprintf(key, sizeof(key), "%.*s", (int)(eq - arg), arg);
    json_object_set_new(into, key, json_string(eq + 1));
}

/* A percentage option: a number with its percent sign ("5%", "2.5%"),
 * returned as a fraction. A bare number is refused, whatever its size:
 * "5" could mean 5% or 500% and "0.05" 0.05% or 5%, and a gate that reads
 * the wrong one passes everything (a slowdown over 500% is ruled out). */
static double percentage(const char *arg, const char *flag, double lo, double hi)
{
    char *end;
    double v = strtod(arg, &end);
    if (end != arg && !*end && isfinite(v))
        die_usage("%s takes a percentage with its sign: %s%%, not %s (a bare number could be a "
                  "fraction or a percentage)", flag, v > 0 && v < 1 ? "e.g. 5" : arg, arg);
    if (end == arg || *end != '%' || end[1] || !(v / 100.0 >= lo && v / 100.0 <= hi))
        die_usage("%s takes a percentage from %g%% to %g%%, e.g. 5%%; got \"%s\"", flag, 100 * lo,
                  100 * hi, arg);
    return v / 100.0;
}

static int count(const char *arg, const char *flag, int lo, int hi)
{
    char *end;
    long v = strtol(arg, &end, 10);
    if (end == arg || *end || v < lo || v > hi)
        die_usage("%s must be a whole number from %d to %d", flag, lo, hi);
    return (int)v;
}

/* A yes/no environment variable: unset or empty is no. */
static bool env_flag(const char *name)
{
    const char *v = getenv(name);
    if (!v || !*v || !strcmp(v, "0") || !strcasecmp(v, "no") || !strcasecmp(v, "false"))
        return false;
    if (!strcmp(v, "1") || !strcasecmp(v, "yes") || !strcasecmp(v, "true"))
        return true;
    die_usage("$%s must be 1, yes or true (or 0, no, false, empty), got \"%s\"", name, v);
}

/* A mistyped option: a short error with the nearest option, not the whole
 * usage. */
static void die_option(const struct option *longopts, const char *arg, bool missing_value)
    __attribute__((noreturn));
static void die_option(const struct option *longopts, const char *arg, bool missing_value)
{
    char name[64];
    const char *s = arg;
    while (*s == '-')
        s++;
    snprintf(name, sizeof(name), "%.*s", (int)strcspn(s, "="), s);
    if (missing_value)
        die_usage("--%s needs a value (see --help)", name);
    const char *names[64];
    size_t n = 0;
    for (const struct option *o = longopts; o->name && n < 64; o++)
        names[n++] = o->name;
    const char *near = suggest_nearest(name, names, n);
    if (near)
        die_usage("unknown option %s; did you mean --%s? (--help lists every option)", arg, near);
    die_usage("unknown option %s (--help lists every option)", arg);
}

int main(int argc, char **argv)
{
    /* One line at a time into a pipe too: a CI log that takes stdout and
     * stderr together must not see a table row split by a log line. */
    setvbuf(stdout, NULL, _IOLBF, 0);
    struct options o = {.max_slowdown = 0.05, .min_ssim = NAN, .max_flip = NAN,
                        .confidence = 0.95, .noise_tolerance = NOISE_TOLERANCE,
                        .max_reruns = 10};
    o.labels = json_object();
    o.filters = json_object();
    o.channels = json_array();
    const char *env_server = getenv("SHADEBENCH_SERVER");
    const char *server = env_server && *env_server ? env_server : "http://127.0.0.1:8460";
    const char *server_b = NULL;
    const char *token = NULL, *token_file = NULL, *argv_token = NULL;
    enum { O_SERVER = 256, O_TOKEN, O_TOKEN_FILE, O_WAIT, O_OUT, O_JUNIT, O_MIN_SSIM, O_MAX_FLIP,
           O_BASELINE, O_SLOWDOWN, O_SERIES, O_TIMEOUT, O_QUIET, O_HELP, O_VERSION, O_RUNS,
           O_RERUNS, O_FAIL_INC, O_ALLOW, O_CONFIDENCE, O_NOISE, O_LABEL, O_FILTER, O_SINCE,
           O_FIGURE, O_SERVER_B, O_NO_FAIL_INC, O_JSON, O_SLURM, O_DEVICES, O_CONSTRAINT,
           O_PARTITION, O_GRES, O_MAX_PARALLEL, O_TIME_LIMIT, O_REQUEUE, O_SHADEBENCHD,
           O_RESUME, O_CHANNEL };
    static const struct option longopts[] = {
        {"server", required_argument, NULL, O_SERVER},
        {"token", required_argument, NULL, O_TOKEN},
        {"token-file", required_argument, NULL, O_TOKEN_FILE},
        {"wait", no_argument, NULL, O_WAIT},
        {"out", required_argument, NULL, O_OUT},
        {"junit", required_argument, NULL, O_JUNIT},
        {"min-ssim", required_argument, NULL, O_MIN_SSIM},
        {"max-flip", required_argument, NULL, O_MAX_FLIP},
        {"baseline", required_argument, NULL, O_BASELINE},
        {"max-slowdown", required_argument, NULL, O_SLOWDOWN},
        {"series", required_argument, NULL, O_SERIES},
        {"timeout", required_argument, NULL, O_TIMEOUT},
        {"quiet", no_argument, NULL, O_QUIET},
        {"help", no_argument, NULL, O_HELP},
        {"version", no_argument, NULL, O_VERSION},
        {"runs", required_argument, NULL, O_RUNS},
        {"max-reruns", required_argument, NULL, O_RERUNS},
        {"fail-inconclusive", no_argument, NULL, O_FAIL_INC},
        {"allow-mismatch", no_argument, NULL, O_ALLOW},
        {"confidence", required_argument, NULL, O_CONFIDENCE},
        {"noise-tolerance", required_argument, NULL, O_NOISE},
        {"label", required_argument, NULL, O_LABEL},
        {"filter", required_argument, NULL, O_FILTER},
        {"since", required_argument, NULL, O_SINCE},
        {"figure", required_argument, NULL, O_FIGURE},
        {"server-b", required_argument, NULL, O_SERVER_B},
        {"no-fail-inconclusive", no_argument, NULL, O_NO_FAIL_INC},
        {"json", no_argument, NULL, O_JSON},
        {"slurm", no_argument, NULL, O_SLURM},
        {"devices", required_argument, NULL, O_DEVICES},
        {"constraint", required_argument, NULL, O_CONSTRAINT},
        {"partition", required_argument, NULL, O_PARTITION},
        {"gres", required_argument, NULL, O_GRES},
        {"max-parallel", required_argument, NULL, O_MAX_PARALLEL},
        {"time-limit", required_argument, NULL, O_TIME_LIMIT},
        {"requeue", no_argument, NULL, O_REQUEUE},
        {"shadebenchd", required_argument, NULL, O_SHADEBENCHD},
        {"resume", required_argument, NULL, O_RESUME},
        {"channel", required_argument, NULL, O_CHANNEL},
        {NULL, 0, NULL, 0},
    };
    /* CI sets the default once for every command; the flags override it. */
    o.fail_inconclusive = env_flag("SHADEBENCH_FAIL_INCONCLUSIVE");
    bool raw_json = false;
    int opt;
    char *end;
    opterr = 0; /* errors are ours: short, with a suggestion */
    while ((opt = getopt_long(argc, argv, ":", longopts, NULL)) != -1) {
        switch (opt) {
        case O_SERVER: server = optarg; break;
        case O_SERVER_B: server_b = optarg; break;
        case O_TOKEN: argv_token = optarg; break;
        case O_TOKEN_FILE: token_file = optarg; break;
        case O_WAIT: o.wait = true; break;
        case O_OUT: o.out_dir = optarg; break;
        case O_JUNIT: o.junit = optarg; break;
        case O_MIN_SSIM:
            o.min_ssim = strtod(optarg, &end);
            if (*end || !(o.min_ssim >= -1 && o.min_ssim <= 1))
                die_usage("--min-ssim must be a number from -1 to 1");
            break;
        case O_MAX_FLIP:
            o.max_flip = strtod(optarg, &end);
            if (*end || !(o.max_flip >= 0 && o.max_flip <= 1))
                die_usage("--max-flip must be a number from 0 to 1");
            break;
        case O_BASELINE: o.baseline = optarg; break;
        case O_SLOWDOWN: o.max_slowdown = percentage(optarg, "--max-slowdown", 0, 100); break;
        case O_CONFIDENCE: o.confidence = percentage(optarg, "--confidence", 0.5, 0.999); break;
        case O_NOISE:
            o.noise_tolerance = !strcmp(optarg, "off") ? INFINITY
                                : percentage(optarg, "--noise-tolerance", 0, 100);
            break;
        case O_RUNS: o.runs = count(optarg, "--runs", 1, 100); break;
        case O_RERUNS: o.max_reruns = count(optarg, "--max-reruns", 0, 1000); break;
        case O_FAIL_INC: o.fail_inconclusive = true; break;
        case O_NO_FAIL_INC: o.fail_inconclusive = false; break;
        case O_JSON: raw_json = true; break;
        case O_SLURM: o.fleet.slurm = true; break;
        case O_DEVICES: o.fleet.devices = optarg; break;
        case O_CONSTRAINT: o.fleet.constraint = optarg; break;
        case O_PARTITION: o.fleet.partition = optarg; break;
        case O_GRES: o.fleet.gres = optarg; break;
        case O_MAX_PARALLEL: o.fleet.max_parallel = count(optarg, "--max-parallel", 1, 100000); break;
        case O_TIME_LIMIT: o.fleet.time_limit = optarg; break;
        case O_REQUEUE: o.fleet.requeue = true; break;
        case O_SHADEBENCHD: o.fleet.shadebenchd = optarg; break;
        case O_RESUME: o.fleet.resume = optarg; break;
        case O_CHANNEL: json_array_append_new(o.channels, json_string(optarg)); break;
        case O_ALLOW: o.allow_mismatch = true; break;
        case O_LABEL: key_value(optarg, "--label", o.labels); break;
        case O_FILTER: key_value(optarg, "--filter", o.filters); break;
        case O_SINCE: o.since = optarg; break;
        case O_SERIES:
        case O_FIGURE:
            if (strcmp(optarg, RK_FRAME_MS) && strcmp(optarg, RK_GPU_MS) &&
                strcmp(optarg, RK_CPU_MS) && (opt == O_SERIES || strcmp(optarg, RK_WORST_SSIM)))
                die_usage("%s must be frame_ms, gpu_ms or cpu_ms%s",
                          opt == O_SERIES ? "--series" : "--figure",
                          opt == O_SERIES ? "" : " (or worst_ssim)");
            if (opt == O_SERIES)
                o.series = optarg;
            else
                o.figure = optarg;
            break;
        case O_TIMEOUT:
            o.timeout_s = strtod(optarg, &end);
            if (*end || !(o.timeout_s > 0))
                die_usage("--timeout must be a number of seconds above 0");
            break;
        case O_QUIET: o.quiet = true; break;
        case O_HELP: usage(stdout); return EXIT_PASS;
        case O_VERSION: printf("shadebench %s\n", PACKAGE_VERSION); return EXIT_PASS;
        case ':': die_option(longopts, argv[optind - 1], true);
        default: die_option(longopts, argv[optind - 1], false);
        }
    }
    if (optind >= argc)
        die_usage("no command given (submit, ab, sweep, plan, gather, compare-devices, history, "
                  "status, list, cancel, fetch, info; --help explains them)");
    const char *cmd = argv[optind];
    int nargs = argc - optind - 1;
    const char *arg = nargs > 0 ? argv[optind + 1] : NULL;
    static const struct {
        const char *name;
        int min, max;
    } commands[] = {
        {"submit", 1, 1}, {"status", 1, 1}, {"cancel", 1, 1}, {"fetch", 1, 1}, {"list", 0, 0},
        {"info", 0, 0},   {"ab", 1, 2},     {"sweep", 0, 1},  {"history", 0, 0}, {"fidelity", 1, 2},
        {"gather", 1, 64}, {"compare-devices", 1, 1}, {"plan", 1, 1},
    };
    size_t k = 0;
    while (k < sizeof(commands) / sizeof(commands[0]) && strcmp(commands[k].name, cmd) != 0)
        k++;
    if (k == sizeof(commands) / sizeof(commands[0])) {
        const char *names[sizeof(commands) / sizeof(commands[0])];
        for (size_t i = 0; i < sizeof(commands) / sizeof(commands[0]); i++)
            names[i] = commands[i].name;
        const char *near = suggest_nearest(cmd, names, sizeof(names) / sizeof(names[0]));
        if (near)
            die_usage("unknown command %s; did you mean %s? (--help lists the commands)", cmd,
                      near);
        die_usage("unknown command %s (--help lists the commands)", cmd);
    }
    if (nargs < commands[k].min || nargs > commands[k].max)
        die_usage("%s takes %s", cmd, commands[k].max == 0 ? "no argument"
                                      : commands[k].min == commands[k].max ? "one argument"
                                      : commands[k].max == 64 ? "one to 64 folders"
                                                              : "one or two arguments");
    const struct fleet_options *fl = &o.fleet;
    bool fleet_flags = fl->devices || fl->constraint || fl->partition || fl->gres ||
                       fl->max_parallel || fl->time_limit || fl->requeue || fl->shadebenchd ||
                       fl->resume;
    if (!strcmp(cmd, "sweep") && (nargs == 0) != (fl->slurm && fl->resume != NULL))
        die_usage(nargs ? "sweep --resume DIR takes no sweep file: the plan is in DIR"
                        : "sweep takes a sweep file (or --slurm --resume DIR)");
    if (fleet_flags && !fl->slurm)
        die_usage("--devices, --constraint, --partition, --gres, --max-parallel, --time-limit, "
                  "--requeue, --shadebenchd and --resume belong to sweep --slurm");
    if (fl->slurm && strcmp(cmd, "sweep") != 0)
        die_usage("--slurm belongs to sweep");
    if (fl->slurm && (o.wait || o.baseline || o.junit))
        die_usage("sweep --slurm always waits for its arrays; --wait, --baseline and --junit "
                  "belong to a daemon's sweep");
    if ((!strcmp(cmd, "fetch") || !strcmp(cmd, "plan")) && !o.out_dir)
        die_usage("%s needs --out DIR", cmd);
    if (!strcmp(cmd, "ab") && (nargs == 2) == (server_b != NULL))
        die_usage("ab takes two job files, or one job file and --server-b URL");
    if (!strcmp(cmd, "sweep") && o.out_dir && !o.wait && !fl->slurm)
        die_usage("sweep --out needs --wait: the table is complete once the sweep ends");
    if (strcmp(cmd, "history") != 0 && (json_object_size(o.filters) || o.since || o.figure))
        die_usage("--filter, --since and --figure belong to history");
    if (raw_json && strcmp(cmd, "info") != 0)
        die_usage("--json belongs to info");
    if ((!isnan(o.min_ssim) || !isnan(o.max_flip)) && strcmp(cmd, "submit") != 0 &&
        strcmp(cmd, "fetch") != 0 && (strcmp(cmd, "sweep") != 0 || fl->slurm))
        die_usage("--min-ssim and --max-flip judge captures against a reference: they belong to "
                  "submit, fetch and sweep");

    /* The token: a file or the environment, so that it need not show in
     * the process list; --token still works, with a warning. */
    char *token_text = NULL, token_source[1100] = "";
    const char *env_token = getenv("SHADEBENCH_TOKEN");
    const char *env_file = getenv("SHADEBENCH_TOKEN_FILE");
    if (argv_token) {
        token = argv_token;
        snprintf(token_source, sizeof(token_source), "--token");
        fprintf(stderr, "shadebench: warning: --token shows the token to every user of this "
                "machine (ps); prefer --token-file or $SHADEBENCH_TOKEN\n");
    } else if (token_file) {
        snprintf(token_source, sizeof(token_source), "--token-file %s", token_file);
        token = token_text = read_token_file(token_file, "--token-file");
    } else if (env_token && *env_token) {
        token = env_token;
        snprintf(token_source, sizeof(token_source), "$SHADEBENCH_TOKEN");
    } else if (env_file && *env_file) {
        snprintf(token_source, sizeof(token_source), "$SHADEBENCH_TOKEN_FILE=%s", env_file);
        token = token_text = read_token_file(env_file, "$SHADEBENCH_TOKEN_FILE");
    }

    curl_global_init(CURL_GLOBAL_DEFAULT);
    struct conn c, cb;
    memset(&cb, 0, sizeof(cb));
    if (!conn_init(&c, server, token) || (server_b && !conn_init(&cb, server_b, token)))
        die_usage("cannot initialise libcurl");
    c.token_source = cb.token_source = token_source;
    int rc;
    char path[256];
    if (!strcmp(cmd, "submit"))
        rc = cmd_submit(&c, &o, arg);
    else if (!strcmp(cmd, "status"))
        rc = cmd_status(&c, arg);
    else if (!strcmp(cmd, "list"))
        rc = cmd_list(&c);
    else if (!strcmp(cmd, "cancel")) {
        snprintf(path, sizeof(path), "/v1/jobs/%s", arg);
        rc = cmd_print(&c, "DELETE", path);
    } else if (!strcmp(cmd, "fetch"))
        rc = cmd_fetch(&c, &o, arg);
    else if (!strcmp(cmd, "info"))
        rc = raw_json ? cmd_print(&c, "GET", "/v1/info") : cmd_info(&c);
    else if (!strcmp(cmd, "ab"))
        rc = cmd_ab(&c, server_b ? &cb : &c, &o, arg, nargs == 2 ? argv[optind + 2] : arg);
    else if (!strcmp(cmd, "sweep"))
        rc = fl->slurm ? cmd_sweep_slurm(&o, arg) : cmd_sweep(&c, &o, arg);
    else if (!strcmp(cmd, "gather"))
        rc = cmd_gather(&o, (const char *const *)&argv[optind + 1], nargs);
    else if (!strcmp(cmd, "plan"))
        rc = cmd_plan(&o, arg);
    else if (!strcmp(cmd, "compare-devices"))
        rc = cmd_compare_devices(&o, arg);
    else if (!strcmp(cmd, "fidelity"))
        rc = cmd_fidelity(&c, &o, arg, nargs == 2 ? argv[optind + 2] : NULL);
    else
        rc = cmd_history(&c, &o);
    conn_finish(&c);
    conn_finish(&cb);
    curl_global_cleanup();
    free(token_text);
    json_decref(o.labels);
    json_decref(o.filters);
    json_decref(o.channels);
    return rc;
}
