#ifndef SHADEBENCH_CHILD_H
#define SHADEBENCH_CHILD_H

/* A helper program run as a child process that never outlives the daemon
 * (issue 34): in a process group of its own (so that a time-out kills what
 * it started), with PR_SET_PDEATHSIG (SIGKILL when the thread that started
 * it ends: a daemon killed with SIGKILL takes its converter with it), its
 * own limits set before exec (RLIMIT_AS, RLIMIT_CPU, nice), SIGPIPE and the
 * signal mask at their defaults, and no file descriptor of the daemon's but
 * stdin (/dev/null), stdout and stderr. The asset converter uses it
 * (daemon/jobs/asset_child.c); any helper the daemon runs should.
 *
 * PR_SET_PDEATHSIG follows the thread that forked, not the process: call
 * child_spawn from a thread that lives as long as the child may (a worker
 * thread, not a request's). It reaches the child itself, not what the
 * child forks: a helper that starts processes of its own kills them (or
 * sets their PDEATHSIG) itself, and child_kill reaches its group. Any
 * thread; GL-free. */

#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

struct child_spec {
    char *const *argv;      /* argv[0] is the program's path */
    int stdout_fd;          /* -1: /dev/null */
    int stderr_fd;          /* -1: the daemon's own stderr (the log) */
    uint64_t address_space; /* RLIMIT_AS in bytes; 0: none */
    uint64_t cpu_s;         /* RLIMIT_CPU in seconds (hard: 5 more); 0: none */
    int nice;               /* the child's nice value (setpriority); 0: the daemon's */
};

/* The child's pid, or -1 with err. It exits 127 when it cannot be set up
 * or its program cannot be run. */
pid_t child_spawn(const struct child_spec *spec, char *err, size_t errlen);
/* SIGKILL to the child's process group and to the child. */
void child_kill(pid_t pid);

#endif
