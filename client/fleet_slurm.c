/* shadebench sweep --slurm, gather and compare-devices: a sweep's points as
 * Slurm job arrays (one per device class), followed with squeue, their
 * failures read from sacct (or, on clusters without accounting, from
 * scontrol while slurmctld still holds the jobs), cancelled with scancel
 * when the client is, resumed by resubmitting only the missing points, and
 * gathered into one sweep result (fleet_gather). Slurm is driven through its
 * commands, as a user would: no library, no daemon of our own.
 * Single-threaded; the signal handler only sets a flag. */
#define _GNU_SOURCE /* realpath */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "client/client.h"
#include "client/fleet.h"
#include "common/fsutil.h"

#define MAX_ARGS 32

static volatile sig_atomic_t interrupted;

static void on_signal(int sig) { interrupted = sig; }

/* Where a command's stderr goes. */
enum cmd_stderr { STDERR_OURS, STDERR_DROP, STDERR_CAPTURE /* into out, after stdout's lines */ };

/* Runs argv, its stdout into *out (NUL-terminated, caller frees). Returns
 * the exit status, or -1 when it could not run (message printed). */
static int run_cmd(char *const argv[], char **out, enum cmd_stderr err_to)
{
    int fds[2];
    if (out)
        *out = NULL;
    if (pipe(fds) != 0)
        return -1;
    pid_t pid = fork();
    if (pid < 0) {
        close(fds[0]);
        close(fds[1]);
        return -1;
    }
    if (pid == 0) {
        /* The child ignores the terminal's Ctrl-C: the client decides what
         * to cancel. */
        signal(SIGINT, SIG_IGN);
        dup2(fds[1], STDOUT_FILENO);
        if (err_to == STDERR_CAPTURE) {
            dup2(fds[1], STDERR_FILENO);
        } else if (err_to == STDERR_DROP) {
            int null = open("/dev/null", O_WRONLY);
            if (null >= 0)
                dup2(null, STDERR_FILENO);
        }
        close(fds[0]);
        close(fds[1]);
        execvp(argv[0], argv);
        fprintf(stderr, "shadebench: cannot run %s: %s\n", argv[0], strerror(errno));
        _exit(127);
    }
    close(fds[1]);
    size_t len = 0, capn = 4096;
    char *buf = malloc(capn);
    for (;;) {
        if (buf && len + 1024 > capn) {
            char *nb = realloc(buf, capn * 2);
            if (!nb) {
                free(buf);
                buf = NULL;
            } else {
                buf = nb;
                capn *= 2;
            }
        }
        char scratch[1024];
        ssize_t n = read(fds[0], buf ? buf + len : scratch, 1023);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            break;
        if (buf)
            len += (size_t)n;
    }
    close(fds[0]);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
        ;
    if (buf)
        buf[len] = '\0';
    if (out)
        *out = buf;
    else
        free(buf);
    if (!WIFEXITED(status))
        return -1;
    return WEXITSTATUS(status) == 127 ? -1 : WEXITSTATUS(status);
}

/* 'text' for sh, inner quotes closed and escaped. */
static void sh_quote(FILE *f, const char *s)
{
    fputc('\'', f);
    for (; *s; s++)
        if (*s == '\'')
            fputs("'\\''", f);
        else
            fputc(*s, f);
    fputc('\'', f);
}

/* The daemon the tasks run: --shadebenchd, else the one beside this client
 * (a build tree, or the same bindir), else shadebenchd on the node's PATH. */
static void find_daemon(const char *given, char *out, size_t cap)
{
    if (given) {
        snprintf(out, cap, "%s", given);
        return;
    }
    char self[PATH_MAX - 16];
    ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
    if (n > 0) {
        self[n] = '\0';
        char *slash = strrchr(self, '/');
        if (slash) {
            *slash = '\0';
            snprintf(out, cap, "%s/shadebenchd", self);
            if (access(out, X_OK) == 0)
                return;
        }
    }
    snprintf(out, cap, "shadebenchd");
}

static bool valid_class(const char *s)
{
    if (!*s || strlen(s) > 64)
        return false;
    for (; *s; s++)
        if (!((*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') || (*s >= '0' && *s <= '9') ||
              *s == '_' || *s == '-' || *s == '.'))
            return false;
    return s[-1] != '.';
}

/* [{"class", "constraint"}] from --devices D1,D2 (or NAME=CONSTRAINT),
 * --constraint C, or neither (one class, "default"). NULL with err. */
static json_t *device_classes(const struct fleet_options *f, char *err, size_t cap)
{
    json_t *classes = json_array();
    if (f->devices) {
        char *list = strdup(f->devices), *save = NULL;
        for (char *tok = strtok_r(list, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
            char *eq = strchr(tok, '=');
            const char *constraint = eq ? eq + 1 : tok;
            if (eq)
                *eq = '\0';
            size_t i;
            json_t *c;
            bool dup = false;
            json_array_foreach(classes, i, c) dup = dup || !strcmp(json_string_value(json_object_get(c, "class")), tok);
            if (!valid_class(tok) || !*constraint || dup) {
                snprintf(err, cap, "--devices: \"%s\" %s", tok,
                         dup ? "is named twice"
                             : "must be a device class name (letters, digits, '_', '-', '.'), "
                               "optionally NAME=CONSTRAINT");
                free(list);
                json_decref(classes);
                return NULL;
            }
            json_array_append_new(classes, json_pack("{s:s, s:s}", "class", tok, "constraint",
                                                     constraint));
        }
        free(list);
        if (f->constraint && json_array_size(classes)) {
            snprintf(err, cap, "--constraint and --devices: give one or the other");
            json_decref(classes);
            return NULL;
        }
    } else if (f->constraint) {
        if (!valid_class(f->constraint)) {
            snprintf(err, cap, "--constraint \"%s\": one node feature names the device class here; "
                               "for an expression use --devices NAME=EXPRESSION",
                     f->constraint);
            json_decref(classes);
            return NULL;
        }
        json_array_append_new(classes, json_pack("{s:s, s:s}", "class", f->constraint,
                                                 "constraint", f->constraint));
    } else {
        json_array_append_new(classes, json_pack("{s:s}", "class", "default"));
    }
    if (!json_array_size(classes)) {
        snprintf(err, cap, "--devices names no device class");
        json_decref(classes);
        return NULL;
    }
    return classes;
}

static bool task_done(const char *dir, const char *cls, json_int_t i)
{
    char path[PATH_MAX];
    snprintf(path, sizeof(path), "%s/tasks/%s/%lld/job.json", dir, cls, (long long)i);
    return access(path, R_OK) == 0;
}

/* "0-4,7,9-10": the indices as sbatch --array takes them. */
static char *array_spec(const json_t *indices)
{
    size_t n = json_array_size(indices), cap = n * 24 + 16;
    char *s = malloc(cap);
    if (!s)
        return NULL;
    s[0] = '\0';
    for (size_t i = 0; i < n;) {
        json_int_t a = json_integer_value(json_array_get(indices, i)), b = a;
        size_t j = i + 1;
        while (j < n && json_integer_value(json_array_get(indices, j)) == b + 1)
            b = json_integer_value(json_array_get(indices, j++));
        size_t used = strlen(s);
        if (a == b)
            snprintf(s + used, cap - used, "%s%lld", used ? "," : "", (long long)a);
        else
            snprintf(s + used, cap - used, "%s%lld-%lld", used ? "," : "", (long long)a, (long long)b);
        i = j;
    }
    return s;
}

static bool write_task_script(const char *dir, const char *daemon, char *err, size_t cap)
{
    char path[PATH_MAX + 64];
    snprintf(path, sizeof(path), "%s/slurm/task.sh", dir);
    char *text = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&text, &len);
    if (!f)
        return false;
    fputs("#!/bin/sh\n"
          "# One point of a shadebench fleet sweep, run by Slurm as an array task on the\n"
          "# node it gives (written by shadebench sweep --slurm). $1 is the device class.\n"
          "# shadebenchd --once writes tasks/CLASS/N whole: it renders into a .partial-\n"
          "# sibling and renames it at the end, so no half-written result is gathered.\n"
          "set -u\n"
          "class=\"$1\"\n"
          "i=\"$SLURM_ARRAY_TASK_ID\"\n"
          "fleet=", f);
    sh_quote(f, dir);
    fputs("\nexec ", f);
    sh_quote(f, daemon);
    /* The GPU Slurm gave the task, whatever the order of EGL's devices; the
     * result's device.selection says which it opened and why. */
    fputs(" --device allocated --once \"$fleet/plan/$i.json\" --out \"$fleet/tasks/$class/$i\" "
          ">/dev/null\n", f);
    bool ok = fclose(f) == 0 && fs_write_atomic(path, text, len) && chmod(path, 0755) == 0;
    free(text);
    if (!ok)
        snprintf(err, cap, "cannot write %s: %s", path, strerror(errno));
    return ok;
}

/* Submits one array of indices for a class; its job id into id. */
static bool submit_array(const char *dir, const json_t *settings, const json_t *cls,
                         const json_t *indices, char *id, size_t idcap, char *err, size_t cap)
{
    char *spec = array_spec(indices);
    if (!spec)
        return false;
    int maxp = (int)json_integer_value(json_object_get(settings, "max_parallel"));
    char array[64 * 1024], name[128], output[PATH_MAX], script[PATH_MAX];
    char partition[256], gres[256], constraint[512], time_limit[128];
    snprintf(array, sizeof(array), "--array=%s%s", spec, "");
    if (maxp > 0) {
        size_t used = strlen(array);
        snprintf(array + used, sizeof(array) - used, "%%%d", maxp);
    }
    free(spec);
    const char *c = json_string_value(json_object_get(cls, "class"));
    snprintf(name, sizeof(name), "--job-name=shadebench-%s", c);
    snprintf(output, sizeof(output), "--output=%s/slurm/logs/%%A_%%a.out", dir);
    snprintf(script, sizeof(script), "%s/slurm/task.sh", dir);
    char *argv[MAX_ARGS];
    int n = 0;
    argv[n++] = "sbatch";
    argv[n++] = "--parsable";
    argv[n++] = name;
    argv[n++] = array;
    argv[n++] = output;
    const char *v;
    if ((v = json_string_value(json_object_get(settings, "partition")))) {
        snprintf(partition, sizeof(partition), "--partition=%s", v);
        argv[n++] = partition;
    }
    if ((v = json_string_value(json_object_get(settings, "gres")))) {
        snprintf(gres, sizeof(gres), "--gres=%s", v);
        argv[n++] = gres;
    }
    if ((v = json_string_value(json_object_get(cls, "constraint")))) {
        snprintf(constraint, sizeof(constraint), "--constraint=%s", v);
        argv[n++] = constraint;
    }
    if ((v = json_string_value(json_object_get(settings, "time_limit")))) {
        snprintf(time_limit, sizeof(time_limit), "--time=%s", v);
        argv[n++] = time_limit;
    }
    argv[n++] = json_is_true(json_object_get(settings, "requeue")) ? "--requeue" : "--no-requeue";
    argv[n++] = script;
    argv[n++] = (char *)c;
    argv[n] = NULL;
    char *out = NULL;
    int rc = run_cmd(argv, &out, STDERR_OURS);
    bool ok = rc == 0 && out && out[0] >= '0' && out[0] <= '9';
    if (ok)
        snprintf(id, idcap, "%.*s", (int)strcspn(out, ";\n "), out);
    else
        snprintf(err, cap, "sbatch refused the array for %s (exit %d)%s%.200s", c, rc,
                 out && *out ? ": " : "", out ? out : "");
    free(out);
    return ok;
}

/* The ids of arrays that still have tasks in Slurm (pending or running). */
static int live_tasks(const json_t *ids, int *pending, int *running)
{
    *pending = *running = 0;
    if (!json_array_size(ids))
        return 0;
    char list[8192] = "";
    size_t i;
    json_t *id;
    json_array_foreach(ids, i, id) {
        size_t used = strlen(list);
        snprintf(list + used, sizeof(list) - used, "%s%s", i ? "," : "", json_string_value(id));
    }
    char *argv[] = {"squeue", "-h", "-r", "-o", "%T", "-j", list, NULL};
    char *out = NULL;
    int rc = run_cmd(argv, &out, STDERR_CAPTURE);
    if (rc != 0) {
        /* squeue refuses a list of ids it no longer knows (every one ended
         * and was purged); any other failure (slurmctld busy or restarting)
         * says nothing, and the caller asks again. */
        bool gone = out && strstr(out, "Invalid job id");
        free(out);
        return gone ? 0 : -1;
    }
    for (char *line = out, *next; line && *line; line = next) {
        next = strchr(line, '\n');
        if (next)
            *next++ = '\0';
        if (!strcmp(line, "RUNNING") || !strcmp(line, "COMPLETING"))
            (*running)++;
        else if (*line)
            (*pending)++;
    }
    free(out);
    return *pending + *running;
}

static void cancel_arrays(const json_t *ids)
{
    size_t i;
    json_t *id;
    char *argv[MAX_ARGS];
    int n = 0;
    argv[n++] = "scancel";
    json_array_foreach(ids, i, id) if (n < MAX_ARGS - 1) argv[n++] = (char *)json_string_value(id);
    argv[n] = NULL;
    if (n > 1 && run_cmd(argv, NULL, STDERR_OURS) == 0) {
        fprintf(stderr, "shadebench: cancelled Slurm array");
        for (int k = 1; k < n; k++)
            fprintf(stderr, " %s", argv[k]);
        fputc('\n', stderr);
    }
}

/* What Slurm says of each task of an array: {"N": {"job_id", "state",
 * "exit_code", "node", "source"}} from sacct, or from scontrol when the
 * cluster keeps no accounting. */
static json_t *array_states(const char *array_id)
{
    json_t *states = json_object();
    char *out = NULL;
    char *sacct[] = {"sacct", "-n", "-P", "-X", "-j", (char *)array_id,
                     "--format=JobID,State,ExitCode,NodeList", NULL};
    if (run_cmd(sacct, &out, STDERR_DROP) == 0 && out && *out) {
        for (char *line = out, *next; *line; line = next) {
            next = strchr(line, '\n');
            if (next)
                *next++ = '\0';
            else
                next = line + strlen(line);
            char *f[4] = {line, NULL, NULL, NULL};
            for (int k = 1; k < 4 && f[k - 1]; k++) {
                char *bar = strchr(f[k - 1], '|');
                if (bar)
                    *bar = '\0', f[k] = bar + 1;
            }
            char *us = strchr(f[0], '_');
            if (!f[3] || !us || strchr(us, '['))
                continue;
            json_object_set_new(states, us + 1,
                                json_pack("{s:s, s:s, s:s, s:s, s:s}", "job_id", f[0], "state",
                                          f[1], "exit_code", f[2], "node", f[3], "source", "sacct"));
        }
        free(out);
        return states;
    }
    free(out);
    out = NULL;
    char *scontrol[] = {"scontrol", "-o", "show", "job", (char *)array_id, NULL};
    if (run_cmd(scontrol, &out, STDERR_DROP) != 0 || !out) {
        free(out);
        return states;
    }
    for (char *line = out, *next; *line; line = next) {
        next = strchr(line, '\n');
        if (next)
            *next++ = '\0';
        else
            next = line + strlen(line);
        char task[32] = "", state[64] = "", exit_code[32] = "", node[256] = "";
        for (char *tok = strtok(line, " "); tok; tok = strtok(NULL, " ")) {
            if (!strncmp(tok, "ArrayTaskId=", 12))
                snprintf(task, sizeof(task), "%s", tok + 12);
            else if (!strncmp(tok, "JobState=", 9))
                snprintf(state, sizeof(state), "%s", tok + 9);
            else if (!strncmp(tok, "ExitCode=", 9))
                snprintf(exit_code, sizeof(exit_code), "%s", tok + 9);
            else if (!strncmp(tok, "NodeList=", 9))
                snprintf(node, sizeof(node), "%s", strcmp(tok + 9, "(null)") ? tok + 9 : "");
        }
        if (!task[0] || strpbrk(task, "-,%"))
            continue; /* a pending range, not one task */
        char job_id[80];
        snprintf(job_id, sizeof(job_id), "%s_%s", array_id, task);
        json_object_set_new(states, task,
                            json_pack("{s:s, s:s, s:s, s:s, s:s}", "job_id", job_id, "state", state,
                                      "exit_code", exit_code, "node", node, "source", "scontrol"));
    }
    free(out);
    return states;
}

/* slurm/states.json: for every task with no folder, what the latest array
 * that ran it says. */
static bool record_states(const char *dir, const json_t *subs, const json_t *plan)
{
    json_t *all = json_object();
    size_t i;
    json_t *s;
    json_array_foreach(subs, i, s) {
        const char *cls = json_string_value(json_object_get(s, "class"));
        json_t *st = array_states(json_string_value(json_object_get(s, "array_job_id")));
        json_t *into = json_object_get(all, cls);
        if (!into)
            json_object_set_new(all, cls, into = json_object());
        const char *task;
        json_t *v;
        json_object_foreach(st, task, v) {
            char *end;
            long long idx = strtoll(task, &end, 10);
            if (!*end && !task_done(dir, cls, idx))
                json_object_set(into, task, v);
        }
        json_decref(st);
    }
    (void)plan;
    char path[PATH_MAX];
    snprintf(path, sizeof(path), "%s/slurm/states.json", dir);
    bool ok = fs_write_json_atomic(path, all);
    json_decref(all);
    return ok;
}

static long long count_done(const char *dir, const json_t *classes, const json_t *plan)
{
    long long done = 0;
    size_t i, k;
    json_t *c, *p;
    json_array_foreach(classes, i, c) json_array_foreach(json_object_get(plan, "points"), k, p)
        done += task_done(dir, json_string_value(json_object_get(c, "class")),
                          json_integer_value(json_object_get(p, "index")));
    return done;
}

/* Follows the arrays until Slurm holds none of their tasks; false when
 * interrupted or out of time (the arrays are then cancelled). */
static bool wait_arrays(const char *dir, const json_t *ids, const json_t *classes,
                        const json_t *plan, const struct options *o)
{
    long long total = (long long)json_array_size(json_object_get(plan, "points")) *
                      (long long)json_array_size(classes);
    bool tty = isatty(STDERR_FILENO);
    double t0 = clock_mono_s();
    char last[160] = "";
    bool unreachable_noted = false;
    for (;;) {
        int pending, running;
        int live = live_tasks(ids, &pending, &running);
        if (live < 0 && !unreachable_noted) {
            fprintf(stderr, "shadebench: squeue failed; asking again each second\n");
            unreachable_noted = true;
        }
        long long done = count_done(dir, classes, plan);
        char line[160];
        snprintf(line, sizeof(line), "fleet: %lld of %lld points done, %d running, %d pending", done,
                 total, running, pending);
        if (!o->quiet && strcmp(line, last)) {
            if (tty)
                fprintf(stderr, "\r%s\033[K", line);
            else
                fprintf(stderr, "%s\n", line);
            snprintf(last, sizeof(last), "%s", line);
        }
        if (live == 0)
            break;
        if (interrupted || (o->timeout_s > 0 && clock_mono_s() - t0 > o->timeout_s)) {
            if (tty && !o->quiet)
                fputc('\n', stderr);
            fprintf(stderr, "shadebench: %s; cancelling the fleet's arrays\n",
                    interrupted ? "interrupted" : "--timeout reached");
            cancel_arrays(ids);
            return false;
        }
        struct timespec ts = {1, 0};
        nanosleep(&ts, NULL);
    }
    if (tty && !o->quiet)
        fputc('\n', stderr);
    return true;
}

/* Gathers dir into itself and prints the comparison; the exit status. */
static int gather_and_print(const struct options *o, const char *const *dirs, int n, const char *out)
{
    char err[1024];
    json_t *fleet = fleet_gather(dirs, n, out, o->series, err, sizeof(err));
    if (!fleet) {
        fprintf(stderr, "shadebench: gather: %s\n", err);
        return EXIT_ERROR;
    }
    json_t *progress = json_object_get(fleet, "progress");
    const char *status = json_string_value(json_object_get(fleet, "status"));
    if (!o->quiet) {
        fleet_view_print(stdout, json_object_get(fleet, "view"));
        size_t i;
        json_t *m;
        json_array_foreach(json_object_get(fleet, "missing"), i, m)
            printf("missing %s: %s\n", json_string_value(json_object_get(m, "job")),
                   json_string_value(json_object_get(m, "error")));
    }
    if (!o->quiet)
        fprintf(stderr, "shadebench: gathered %lld of %lld points into %s (%s)\n",
            (long long)json_integer_value(json_object_get(progress, "points_done")),
            (long long)json_integer_value(json_object_get(progress, "points_total")), out,
            strcmp(status, "done") ? "partial: --resume DIR runs the missing points" : "complete");
    /* A point whose job failed is a result, and a failure of the run. */
    bool failed = false;
    size_t i;
    json_t *row;
    json_array_foreach(json_object_get(fleet, "points"), i, row)
        failed = failed || strcmp(json_string_value(json_object_get(row, "status")), "done") != 0;
    json_decref(fleet);
    return failed ? EXIT_FAIL : EXIT_PASS;
}

int cmd_gather(const struct options *o, const char *const *dirs, int n)
{
    const char *out = o->out_dir ? o->out_dir : dirs[0];
    if (!fs_mkdir_p(out)) {
        fprintf(stderr, "shadebench: cannot create %s: %s\n", out, strerror(errno));
        return EXIT_ERROR;
    }
    return gather_and_print(o, dirs, n, out);
}

int cmd_plan(const struct options *o, const char *sweep_file)
{
    char err[PATH_MAX + 1024], path[PATH_MAX + 64];
    snprintf(path, sizeof(path), "%s/plan/points.json", o->out_dir);
    if (access(path, F_OK) == 0) {
        fprintf(stderr, "shadebench: %s holds a plan already\n", o->out_dir);
        return EXIT_ERROR;
    }
    json_t *body = load_json_file("sweep file", sweep_file, err, sizeof(err));
    bool ok = json_is_object(body) && fleet_plan_write(body, o->out_dir, err, sizeof(err));
    if (!ok)
        fprintf(stderr, "shadebench: %s\n", !body ? err : json_is_object(body) ? err
                                                     : "a sweep is a JSON object");
    json_decref(body);
    json_t *plan = ok ? fleet_plan_read(o->out_dir, err, sizeof(err)) : NULL;
    if (!plan)
        return EXIT_ERROR;
    size_t n = json_array_size(json_object_get(plan, "points"));
    printf("%zu points in %s/plan; run each on a runner labelled LABEL with\n"
           "  shadebenchd --device allocated --once %s/plan/N.json --out %s/tasks/LABEL/N\n"
           "for N from 0 to %zu, then: shadebench gather DIR...\n",
           n, o->out_dir, o->out_dir, o->out_dir, n ? n - 1 : 0);
    json_decref(plan);
    return EXIT_PASS;
}

int cmd_compare_devices(const struct options *o, const char *dir)
{
    char path[PATH_MAX];
    snprintf(path, sizeof(path), "%s/sweep.json", dir);
    json_error_t jerr;
    json_t *fleet = json_load_file(path, 0, &jerr);
    if (!fleet || strcmp(json_string_value(json_object_get(fleet, "kind")) ?
                         json_string_value(json_object_get(fleet, "kind")) : "", "fleet")) {
        fprintf(stderr, "shadebench: %s: %s\n", path,
                fleet ? "not a gathered fleet sweep (shadebench gather writes one)" : jerr.text);
        json_decref(fleet);
        return EXIT_ERROR;
    }
    /* Each class's own table, so --series may choose another reading. */
    json_t *groups = json_array(), *d;
    size_t i;
    bool ok = true;
    json_array_foreach(json_object_get(fleet, "devices"), i, d) {
        const char *cls = json_string_value(json_object_get(d, "class"));
        snprintf(path, sizeof(path), "%s/devices/%s/sweep.json", dir, cls);
        json_t *sweep = json_load_file(path, 0, &jerr);
        if (!sweep) {
            fprintf(stderr, "shadebench: %s: %s\n", path, jerr.text);
            ok = false;
            break;
        }
        json_array_append_new(groups, json_pack("{s:s, s:O, s:o}", "class", cls, "device",
                                                json_object_get(sweep, "device"), "sweep", sweep));
    }
    if (ok) {
        json_t *view = fleet_device_view(groups, o->series);
        fleet_view_print(stdout, view);
        json_decref(view);
    }
    json_decref(groups);
    json_decref(fleet);
    return ok ? EXIT_PASS : EXIT_ERROR;
}

int cmd_sweep_slurm(const struct options *o, const char *sweep_file)
{
    const struct fleet_options *fo = &o->fleet;
    const char *dir = fo->resume ? fo->resume : o->out_dir;
    double t_start = clock_mono_s();
    char err[PATH_MAX + 1024], path[PATH_MAX + 64];
    json_t *settings = NULL, *classes = NULL, *plan = NULL, *subs = NULL, *ids = json_array();
    int rc = EXIT_ERROR;
    if (!dir) {
        fprintf(stderr, "shadebench: sweep --slurm needs --out DIR, a folder every node can "
                        "reach (or --resume DIR)\n");
        goto out;
    }
    if (!fo->resume) {
        char real[PATH_MAX - 64];
        snprintf(path, sizeof(path), "%s/plan/points.json", dir);
        if (access(path, F_OK) == 0) {
            fprintf(stderr, "shadebench: %s holds a fleet sweep already: --resume %s completes "
                            "it, or choose another --out\n", dir, dir);
            goto out;
        }
        char *resolved = fs_mkdir_p(dir) ? realpath(dir, NULL) : NULL;
        if (!resolved || strlen(resolved) >= sizeof(real)) {
            fprintf(stderr, "shadebench: cannot create %s: %s\n", dir,
                    resolved ? "the path is too long" : strerror(errno));
            free(resolved);
            goto out;
        }
        snprintf(real, sizeof(real), "%s", resolved);
        free(resolved);
        json_t *body = load_json_file("sweep file", sweep_file, err, sizeof(err));
        if (!json_is_object(body)) {
            fprintf(stderr, "shadebench: %s\n", body ? "a sweep is a JSON object" : err);
            json_decref(body);
            goto out;
        }
        sweep_add_labels(body, o->labels);
        classes = device_classes(fo, err, sizeof(err));
        bool planned = classes && fleet_plan_write(body, real, err, sizeof(err));
        json_decref(body);
        if (!planned) {
            fprintf(stderr, "shadebench: %s\n", err);
            goto out;
        }
        char daemon[PATH_MAX];
        find_daemon(fo->shadebenchd, daemon, sizeof(daemon));
        settings = json_pack("{s:s, s:O, s:i, s:b}", "fleet", real, "classes", classes,
                             "max_parallel", fo->max_parallel, "requeue", fo->requeue);
        json_object_set_new(settings, "shadebenchd", json_string(daemon));
        if (fo->partition)
            json_object_set_new(settings, "partition", json_string(fo->partition));
        if (fo->gres)
            json_object_set_new(settings, "gres", json_string(fo->gres));
        if (fo->time_limit)
            json_object_set_new(settings, "time_limit", json_string(fo->time_limit));
        snprintf(path, sizeof(path), "%s/slurm/logs", real);
        if (!fs_mkdir_p(path) || !write_task_script(real, daemon, err, sizeof(err))) {
            fprintf(stderr, "shadebench: %s\n", err[0] ? err : strerror(errno));
            goto out;
        }
        snprintf(path, sizeof(path), "%s/slurm/settings.json", real);
        if (!fs_write_json_atomic(path, settings)) {
            fprintf(stderr, "shadebench: cannot write %s: %s\n", path, strerror(errno));
            goto out;
        }
        subs = json_array();
    } else {
        snprintf(path, sizeof(path), "%s/slurm/settings.json", dir);
        json_error_t jerr;
        settings = json_load_file(path, 0, &jerr);
        snprintf(path, sizeof(path), "%s/slurm/submissions.json", dir);
        subs = json_load_file(path, 0, &jerr);
        if (!settings || !json_is_array(subs)) {
            fprintf(stderr, "shadebench: %s is not a fleet folder of sweep --slurm: %s\n", dir,
                    jerr.text);
            goto out;
        }
        /* Options given now override the first submission's. */
        if (fo->max_parallel)
            json_object_set_new(settings, "max_parallel", json_integer(fo->max_parallel));
        if (fo->partition)
            json_object_set_new(settings, "partition", json_string(fo->partition));
        if (fo->requeue)
            json_object_set_new(settings, "requeue", json_true());
        classes = json_incref(json_object_get(settings, "classes"));
        size_t i;
        json_t *s;
        json_array_foreach(subs, i, s) json_array_append(ids, json_object_get(s, "array_job_id"));
        int pending, running, live = live_tasks(ids, &pending, &running);
        if (live < 0) {
            fprintf(stderr, "shadebench: squeue failed: cannot tell whether the fleet's arrays "
                            "still run; resume once Slurm answers\n");
            goto out;
        }
        if (live > 0) {
            fprintf(stderr, "shadebench: the fleet's arrays still have %d tasks in Slurm (%d "
                            "running): wait for them, or scancel them, then resume\n",
                    pending + running, running);
            goto out;
        }
        json_array_clear(ids);
        dir = json_string_value(json_object_get(settings, "fleet"));
    }
    plan = fleet_plan_read(dir, err, sizeof(err));
    if (!plan) {
        fprintf(stderr, "shadebench: %s\n", err);
        goto out;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof(sa));
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    double t0 = clock_mono_s();
    size_t i, k;
    json_t *c, *p;
    int submitted = 0;
    json_array_foreach(classes, i, c) {
        const char *cls = json_string_value(json_object_get(c, "class"));
        json_t *indices = json_array();
        json_array_foreach(json_object_get(plan, "points"), k, p) {
            json_int_t idx = json_integer_value(json_object_get(p, "index"));
            if (!task_done(dir, cls, idx))
                json_array_append_new(indices, json_integer(idx));
        }
        if (!json_array_size(indices)) {
            json_decref(indices);
            continue;
        }
        char id[64];
        if (!submit_array(dir, settings, c, indices, id, sizeof(id), err, sizeof(err))) {
            fprintf(stderr, "shadebench: %s\n", err);
            json_decref(indices);
            cancel_arrays(ids);
            goto out;
        }
        char *spec = array_spec(indices);
        json_array_append_new(subs, json_pack("{s:s, s:s, s:s, s:I}", "class", cls,
                                              "array_job_id", id, "indices", spec ? spec : "",
                                              "tasks", (json_int_t)json_array_size(indices)));
        free(spec);
        json_array_append_new(ids, json_string(id));
        snprintf(path, sizeof(path), "%s/slurm/submissions.json", dir);
        fs_write_json_atomic(path, subs);
        if (!o->quiet)
            fprintf(stderr, "shadebench: %s: Slurm array %s, %zu tasks\n", cls, id,
                    json_array_size(indices));
        submitted += (int)json_array_size(indices);
        json_decref(indices);
        if (interrupted) {
            cancel_arrays(ids);
            goto out;
        }
    }
    if (!submitted && !o->quiet)
        fprintf(stderr, "shadebench: every point has its result; gathering\n");
    else if (!o->quiet)
        fprintf(stderr, "shadebench: planned and submitted %d tasks in %.2f s\n", submitted,
                clock_mono_s() - t_start);
    bool finished = wait_arrays(dir, ids, classes, plan, o);
    if (!record_states(dir, subs, plan))
        fprintf(stderr, "shadebench: cannot write %s/slurm/states.json: %s\n", dir, strerror(errno));
    if (!o->quiet)
        fprintf(stderr, "shadebench: the arrays took %.1f s\n", clock_mono_s() - t0);
    const char *dirs[1] = {dir};
    double t_gather = clock_mono_s();
    rc = gather_and_print(o, dirs, 1, dir);
    if (!o->quiet)
        fprintf(stderr, "shadebench: gathered in %.2f s\n", clock_mono_s() - t_gather);
    if (!finished)
        rc = interrupted ? 128 + interrupted : EXIT_ERROR;
out:
    json_decref(ids);
    json_decref(subs);
    json_decref(plan);
    json_decref(classes);
    json_decref(settings);
    return rc;
}
