#!/usr/bin/env python3
"""No orphan converter (issue 34, item 6): a daemon killed with SIGKILL in
the middle of a conversion takes its converter with it (PR_SET_PDEATHSIG),
and the daemon started again on the same state directory removes what the
conversion left (the upload's and the cache's temporaries).

The converter here is a stand-in (--asset-converter) that behaves as the
real one does while it writes: it creates its cache's temporary beside
OUT_CACHE (asset_file_write's OUT.XXXXXX), writes a megabyte into it, says
its pid, and then takes its time. Before the fix it ran on after the
daemon died (the red team's kept running for minutes and left a 96 MB
temporary behind the restarted daemon's sweep)."""

import os
import shutil
import signal
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import testlib  # noqa: E402
from testlib import Daemon, check, stop_and_check  # noqa: E402
from e2e_assets import glb, put  # noqa: E402

STAND_IN = r'''#!/usr/bin/env python3
import os, sys, tempfile, time
out = sys.argv[3]
fd, tmp = tempfile.mkstemp(prefix=os.path.basename(out) + ".", dir=os.path.dirname(out))
os.write(fd, b"\0" * (1 << 20))
with open(os.path.join(os.environ["ORPHAN_MARK"], "pid.tmp"), "w") as f:
    f.write("%d %s" % (os.getpid(), tmp))
os.rename(os.path.join(os.environ["ORPHAN_MARK"], "pid.tmp"),
          os.path.join(os.environ["ORPHAN_MARK"], "pid"))
time.sleep(600)
'''


def running(pid):
    """The process exists and is not a zombie (a container's init may be
    slow to reap)."""
    try:
        with open("/proc/%d/stat" % pid) as f:
            state = f.read().rsplit(")", 1)[1].split()[0]
        return state not in ("Z", "X")
    except OSError:
        return False


def main():
    d = None
    mark = tempfile.mkdtemp(prefix="e2e_orphans.")
    try:
        stand_in = os.path.join(mark, "converter")
        with open(stand_in, "w") as f:
            f.write(STAND_IN)
        os.chmod(stand_in, 0o755)
        state = os.path.join(mark, "state")
        d = Daemon("--state-dir", state, "--asset-converter", stand_in,
                   env={"ORPHAN_MARK": mark})
        def upload():
            try:
                put(d, "slow.glb", glb(5.0), timeout=30)
            except OSError:
                pass  # the daemon is killed under it
        t = threading.Thread(target=upload, daemon=True)
        t.start()
        pid_file = os.path.join(mark, "pid")
        deadline = time.time() + 60 * testlib.TIME_SCALE
        while not os.path.exists(pid_file) and time.time() < deadline:
            time.sleep(0.05)
        if not check(os.path.exists(pid_file), "the converter started"):
            return
        with open(pid_file) as f:
            pid_text, tmp = f.read().split(" ", 1)
        pid = int(pid_text)
        check(running(pid) and os.path.exists(tmp),
              "the converter runs and has written its temporary (%s)" % tmp)

        # SIGKILL: the daemon gets no chance to clean up.
        d.proc.send_signal(signal.SIGKILL)
        d.proc.wait()
        d.log.close()
        deadline = time.time() + 10 * testlib.TIME_SCALE
        while running(pid) and time.time() < deadline:
            time.sleep(0.05)
        alive = running(pid)
        check(not alive, "the converter (pid %d) died with the daemon" % pid)
        if alive:
            os.kill(pid, signal.SIGKILL)

        # Started again on the same state: nothing of the conversion is left.
        d = Daemon("--state-dir", state, "--asset-converter", stand_in,
                   env={"ORPHAN_MARK": mark})
        left = [n for n in os.listdir(os.path.join(state, "assets"))
                if n.startswith(("upload-", "convert-")) or ".tmp" in n]
        check(not left, "no temporary left after the restart (%s)" % left)
        check(not os.path.exists(tmp), "the converter's temporary %s is gone" % tmp)
        code, _ = d.json("GET", "/healthz")
        check(code == 200, "the restarted daemon is healthy (%d)" % code)
        code, body = d.json("GET", "/v1/assets/slow.glb")
        check(code == 404, "the interrupted upload left no asset (%d %s)" % (code, body))
    finally:
        if d is not None:
            stop_and_check(d)
        if not testlib.failures:
            shutil.rmtree(mark, ignore_errors=True)
    testlib.finish("e2e_orphans")


if __name__ == "__main__":
    main()
