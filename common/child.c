/* closefrom (glibc 2.34). */
#define _GNU_SOURCE
/* Helper programs as child processes that die with the daemon (child.h). */
#include "common/child.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <unistd.h>

pid_t child_spawn(const struct child_spec *spec, char *err, size_t errlen)
{
    int devnull = open("/dev/null", O_RDWR | O_CLOEXEC);
    if (devnull < 0) {
        snprintf(err, errlen, "cannot open /dev/null: %s", strerror(errno));
        return -1;
    }
    struct rlimit mem = {spec->address_space, spec->address_space};
    struct rlimit cpu = {spec->cpu_s, spec->cpu_s + 5};
    sigset_t none;
    sigemptyset(&none);
    pid_t parent = getpid();
    pid_t pid = fork();
    if (pid < 0) {
        snprintf(err, errlen, "cannot start %s: %s", spec->argv[0], strerror(errno));
        close(devnull);
        return -1;
    }
    if (pid == 0) {
        /* The child of a threaded process: async-signal-safe calls only. */
        setpgid(0, 0);
        if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != parent)
            _exit(127); /* the daemon is gone already: nothing to do it for */
        struct sigaction dfl = {.sa_handler = SIG_DFL};
        sigaction(SIGPIPE, &dfl, NULL);        /* the daemon ignores it */
        sigprocmask(SIG_SETMASK, &none, NULL); /* and blocks SIGTERM for sigwait */
        int out = spec->stdout_fd >= 0 ? spec->stdout_fd : devnull;
        if (dup2(devnull, 0) < 0 || dup2(out, 1) < 0 ||
            (spec->stderr_fd >= 0 && dup2(spec->stderr_fd, 2) < 0))
            _exit(127);
        closefrom(3);
        if (mem.rlim_cur)
            setrlimit(RLIMIT_AS, &mem);
        if (cpu.rlim_cur)
            setrlimit(RLIMIT_CPU, &cpu);
        if (spec->nice)
            setpriority(PRIO_PROCESS, 0, spec->nice);
        execv(spec->argv[0], spec->argv);
        _exit(127);
    }
    /* Its own process group from the parent's side too: whichever of the
     * two runs first, a kill of -pid after this reaches it. */
    setpgid(pid, pid);
    close(devnull);
    return pid;
}

void child_kill(pid_t pid)
{
    if (pid <= 0)
        return;
    kill(-pid, SIGKILL);
    kill(pid, SIGKILL);
}
