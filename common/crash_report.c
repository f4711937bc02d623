/* pthread_getname_np, gettid. */
#define _GNU_SOURCE
/* Fatal signals reported to the log (crash_report.h). */
#include "common/crash_report.h"

#include <execinfo.h>
#include <stdbool.h>
#include <pthread.h>
#include <signal.h>
#include <string.h>
#include <unistd.h>

#if defined(__SANITIZE_ADDRESS__)
#define CRASH_REPORT_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CRASH_REPORT_SANITIZED 1
#endif
#endif

static const char *program_name = "shadebench";

static void put(const char *s) { (void)!write(STDERR_FILENO, s, strlen(s)); }

/* Decimal, without stdio (which is not async-signal-safe). */
static void put_long(long v)
{
    char buf[24], *p = buf + sizeof(buf);
    *--p = '\0';
    bool negative = v < 0;
    unsigned long u = negative ? 0UL - (unsigned long)v : (unsigned long)v;
    do {
        *--p = (char)('0' + u % 10);
        u /= 10;
    } while (u);
    if (negative)
        *--p = '-';
    put(p);
}

static const char *signal_name(int sig)
{
    switch (sig) {
    case SIGSEGV: return "SIGSEGV";
    case SIGBUS: return "SIGBUS";
    case SIGFPE: return "SIGFPE";
    case SIGILL: return "SIGILL";
    case SIGABRT: return "SIGABRT";
    default: return "a fatal signal";
    }
}

static void on_fatal(int sig)
{
    /* SA_RESETHAND gave the signal its default action back: a second fault
     * in here, or the raise below, ends the process as it would have. */
    char name[32] = "";
    pthread_getname_np(pthread_self(), name, sizeof(name));
    put(program_name);
    put(": fatal ");
    put(signal_name(sig));
    put(" (");
    put_long(sig);
    put(") in thread ");
    put_long((long)gettid());
    if (name[0]) {
        put(" \"");
        put(name);
        put("\"");
    }
    put("; its stack:\n");
    void *frames[64];
    int n = backtrace(frames, 64);
    backtrace_symbols_fd(frames, n, STDERR_FILENO);
    put(program_name);
    put(": end of the stack (offsets: addr2line -f -e BINARY OFFSET)\n");
    raise(sig);
}

void crash_report_install(const char *program)
{
#ifdef CRASH_REPORT_SANITIZED
    (void)program;
#else
    if (program && program[0])
        program_name = program;
    /* backtrace loads libgcc's unwinder on its first call, which allocates:
     * done now, so that the handler need not, on a heap that may be the
     * reason it runs. */
    void *warm[1];
    backtrace(warm, 1);
    static const int fatal[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
    struct sigaction sa;
    memset(&sa, 0, sizeof(sa));
    sa.sa_handler = on_fatal;
    sa.sa_flags = SA_RESETHAND | SA_NODEFER;
    sigemptyset(&sa.sa_mask);
    for (size_t i = 0; i < sizeof(fatal) / sizeof(fatal[0]); i++)
        sigaction(fatal[i], &sa, NULL);
#endif
}
