#ifndef SHADEBENCH_CRASH_REPORT_H
#define SHADEBENCH_CRASH_REPORT_H

/* What a daemon that dies of a fatal signal leaves in its log: the signal,
 * the thread it hit (its kernel id and name) and that thread's stack, as
 * backtrace_symbols_fd writes it (functions the binary exports by name, the
 * rest as offsets for addr2line), written to stderr (the log, or the
 * journal under systemd) with nothing but write(2), before the signal is
 * raised again with its default action (the exit status and a core dump
 * stay as they were). A heap that glibc finds corrupt aborts in free() or
 * malloc(): the stack then says which free found it. SIGSEGV, SIGBUS,
 * SIGFPE, SIGILL and SIGABRT.
 *
 * Not installed under AddressSanitizer, whose own report says more. Call
 * once from main before any thread starts; the handler runs on whichever
 * thread the signal hits. */

/* Installs the handlers; the program's name heads each report. */
void crash_report_install(const char *program);

#endif
