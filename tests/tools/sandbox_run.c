/* Test helper: runs a command under the seccomp rules that systemd applies
 * for the unit's hardening options, so that each option can be tried on the
 * daemon and llvmpipe without systemd as init:
 *   sandbox-run [--allow FILE] [--families AF_UNIX,AF_INET,...] [--mdwe]
 *               [--no-realtime] [--no-namespaces] [--lock-personality] -- CMD...
 * --allow FILE     SystemCallFilter=: only the syscalls named in FILE (one a
 *                  line), others fail with EPERM (SystemCallErrorNumber=EPERM)
 * --families LIST  RestrictAddressFamilies=: socket() of other families
 *                  fails with EAFNOSUPPORT
 * --mdwe           MemoryDenyWriteExecute=yes: no mapping both writable and
 *                  executable, no mprotect() or shmat() to executable
 * --no-realtime    RestrictRealtime=yes
 * --no-namespaces  RestrictNamespaces=yes
 * --lock-personality LockPersonality=yes
 * The rules follow systemd's src/shared/seccomp-util.c. */
#define _GNU_SOURCE
#include <errno.h>
#include <stdbool.h>
#include <sched.h>
#include <seccomp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/personality.h>
#include <sys/prctl.h>
#include <sys/shm.h>
#include <sys/socket.h>
#include <unistd.h>

static int load(scmp_filter_ctx ctx, const char *what)
{
    int rc = seccomp_load(ctx);
    seccomp_release(ctx);
    if (rc != 0)
        fprintf(stderr, "sandbox-run: cannot load the %s filter: %s\n", what, strerror(-rc));
    return rc;
}

static int allow_list(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "sandbox-run: cannot read %s\n", path);
        return -1;
    }
    scmp_filter_ctx ctx = seccomp_init(SCMP_ACT_ERRNO(EPERM));
    char name[128];
    int n = 0;
    while (fscanf(f, "%127s", name) == 1) {
        int nr = seccomp_syscall_resolve_name(name);
        if (nr == __NR_SCMP_ERROR)
            continue; /* not on this architecture */
        if (seccomp_rule_add(ctx, SCMP_ACT_ALLOW, nr, 0) == 0)
            n++;
    }
    fclose(f);
    if (n == 0) {
        fprintf(stderr, "sandbox-run: %s allows no syscall\n", path);
        seccomp_release(ctx);
        return -1;
    }
    return load(ctx, "syscall allow-list");
}

static int families(const char *list)
{
    static const struct {
        const char *name;
        int family;
    } known[] = {{"AF_UNIX", AF_UNIX}, {"AF_INET", AF_INET}, {"AF_INET6", AF_INET6},
                 {"AF_NETLINK", AF_NETLINK}, {"AF_PACKET", AF_PACKET}};
    bool allowed[64] = {false};
    char copy[256];
    snprintf(copy, sizeof(copy), "%s", list);
    for (char *tok = strtok(copy, ", "); tok; tok = strtok(NULL, ", ")) {
        bool found = false;
        for (size_t i = 0; i < sizeof(known) / sizeof(known[0]); i++)
            if (strcmp(tok, known[i].name) == 0)
                allowed[known[i].family] = found = true;
        if (!found) {
            fprintf(stderr, "sandbox-run: unknown address family %s\n", tok);
            return -1;
        }
    }
    scmp_filter_ctx ctx = seccomp_init(SCMP_ACT_ALLOW);
    for (int fam = 0; fam < 64; fam++)
        if (!allowed[fam])
            seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EAFNOSUPPORT), SCMP_SYS(socket), 1,
                             SCMP_A0(SCMP_CMP_EQ, (scmp_datum_t)fam));
    return load(ctx, "address family");
}

static int mdwe(void)
{
    scmp_filter_ctx ctx = seccomp_init(SCMP_ACT_ALLOW);
    seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EPERM), SCMP_SYS(mmap), 1,
                     SCMP_A2(SCMP_CMP_MASKED_EQ, PROT_EXEC | PROT_WRITE, PROT_EXEC | PROT_WRITE));
    seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EPERM), SCMP_SYS(mprotect), 1,
                     SCMP_A2(SCMP_CMP_MASKED_EQ, PROT_EXEC, PROT_EXEC));
    seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EPERM), SCMP_SYS(pkey_mprotect), 1,
                     SCMP_A2(SCMP_CMP_MASKED_EQ, PROT_EXEC, PROT_EXEC));
    seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EPERM), SCMP_SYS(shmat), 1,
                     SCMP_A2(SCMP_CMP_MASKED_EQ, SHM_EXEC, SHM_EXEC));
    return load(ctx, "MemoryDenyWriteExecute");
}

static int realtime(void)
{
    scmp_filter_ctx ctx = seccomp_init(SCMP_ACT_ALLOW);
    /* Any policy but SCHED_OTHER, SCHED_BATCH and SCHED_IDLE is refused. */
    for (int policy = 0; policy < 8; policy++)
        if (policy != SCHED_OTHER && policy != SCHED_BATCH && policy != SCHED_IDLE)
            seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EPERM), SCMP_SYS(sched_setscheduler), 1,
                             SCMP_A1(SCMP_CMP_EQ, (scmp_datum_t)policy));
    return load(ctx, "RestrictRealtime");
}

static int namespaces(void)
{
    const scmp_datum_t any_ns = CLONE_NEWNS | CLONE_NEWUTS | CLONE_NEWIPC | CLONE_NEWUSER |
                                CLONE_NEWPID | CLONE_NEWNET | CLONE_NEWCGROUP;
    scmp_filter_ctx ctx = seccomp_init(SCMP_ACT_ALLOW);
    seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EPERM), SCMP_SYS(setns), 0);
    for (unsigned bit = 0; bit < 64; bit++) {
        scmp_datum_t flag = (scmp_datum_t)1 << bit;
        if (!(any_ns & flag))
            continue;
        seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EPERM), SCMP_SYS(unshare), 1,
                         SCMP_A0(SCMP_CMP_MASKED_EQ, flag, flag));
        seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EPERM), SCMP_SYS(clone), 1,
                         SCMP_A0(SCMP_CMP_MASKED_EQ, flag, flag));
    }
    /* clone3 passes its flags in memory that seccomp cannot read: systemd
     * makes it fail with ENOSYS so that libc falls back to clone. */
    seccomp_rule_add(ctx, SCMP_ACT_ERRNO(ENOSYS), SCMP_SYS(clone3), 0);
    return load(ctx, "RestrictNamespaces");
}

static int personality_lock(void)
{
    unsigned long current = (unsigned long)personality(0xffffffff);
    scmp_filter_ctx ctx = seccomp_init(SCMP_ACT_ALLOW);
    seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EPERM), SCMP_SYS(personality), 1,
                     SCMP_A0(SCMP_CMP_NE, (scmp_datum_t)current));
    return load(ctx, "LockPersonality");
}

int main(int argc, char **argv)
{
    int i = 1;
    /* NoNewPrivileges=yes, which seccomp needs without CAP_SYS_ADMIN anyway. */
    if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0) {
        perror("sandbox-run: PR_SET_NO_NEW_PRIVS");
        return 125;
    }
    /* The filters come last to first: the allow-list is loaded at the end,
     * so that loading the others needs no syscall outside it. */
    const char *allow = NULL;
    for (; i < argc && strcmp(argv[i], "--") != 0; i++) {
        int rc = 0;
        if (strcmp(argv[i], "--allow") == 0 && i + 1 < argc)
            allow = argv[++i];
        else if (strcmp(argv[i], "--families") == 0 && i + 1 < argc)
            rc = families(argv[++i]);
        else if (strcmp(argv[i], "--mdwe") == 0)
            rc = mdwe();
        else if (strcmp(argv[i], "--no-realtime") == 0)
            rc = realtime();
        else if (strcmp(argv[i], "--no-namespaces") == 0)
            rc = namespaces();
        else if (strcmp(argv[i], "--lock-personality") == 0)
            rc = personality_lock();
        else {
            fprintf(stderr, "sandbox-run: unknown option %s\n", argv[i]);
            return 125;
        }
        if (rc != 0)
            return 125;
    }
    if (i + 1 >= argc) {
        fprintf(stderr, "usage: sandbox-run [OPTION]... -- COMMAND [ARG]...\n");
        return 125;
    }
    if (allow && allow_list(allow) != 0)
        return 125;
    execvp(argv[i + 1], argv + i + 1);
    perror("sandbox-run: exec");
    return 126;
}
