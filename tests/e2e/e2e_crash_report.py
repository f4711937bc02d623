"""A daemon killed by a fatal signal says so in its log: which signal, in
which thread, and that thread's stack with the binary's functions named
(common/crash_report.h), and still ends as the signal's default action
ends it (the exit status a supervisor or a test sees, a core dump where
enabled). Before it, a heap that glibc found corrupt ended the daemon with
only glibc's one line (CI, 2026-11-27): nothing said which thread or which
free() found it."""

import os
import signal
import time

import testlib
from testlib import check

testlib.skip_without_egl()

for sig, name in ((signal.SIGSEGV, "SIGSEGV"), (signal.SIGABRT, "SIGABRT")):
    d = testlib.Daemon()
    try:
        status, _ = d.json("POST", "/v1/jobs", {"frames": 2, "warmup_frames": 0,
                                                "scene": {"width": 32, "height": 24}})
        check(status == 202, "a job is accepted before the signal (%d)" % status)
        os.kill(d.proc.pid, sig)
        try:
            code = d.proc.wait(timeout=30 * testlib.TIME_SCALE)
        except Exception:
            code = None
        check(code == -sig, "%s: the daemon ends by the signal, as its default action does "
              "(exit status %s)" % (name, code))
        d.log.flush()
        with open(d.log_path) as f:
            log = f.read()
        head = "shadebenchd: fatal %s (%d) in thread " % (name, sig)
        check(head in log, "%s: the log names the signal and the thread" % name)
        stack = log.split(head, 1)[1] if head in log else ""
        check("its stack:" in stack and "end of the stack" in stack,
              "%s: the log holds the thread's stack" % name)
        check("(main+" in stack or "_start" in stack,
              "%s: the stack's frames are named (the binary exports its functions)" % name)
    finally:
        if d.alive():
            d.proc.kill()
            d.proc.wait()
        d.log.close()
        d.cleanup()
    time.sleep(0.1)

testlib.finish("e2e_crash_report")
