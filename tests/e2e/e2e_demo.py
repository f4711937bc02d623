"""tools/demo honours the port (and host) in SHADEBENCH_SERVER, starting
shadebenchd there, and shows a job's progress while it runs. Run with
SETUP=0 (the build exists) and a small job in place of the thesis jobs
(DEMO_JOBS), so that it takes seconds. Before: the daemon was started on
8460 whatever the URL said, and the demo waited for the URL's port until it
gave up; a running job printed nothing until it ended."""

import json
import os
import re
import signal
import socket
import subprocess
import tempfile
import time
import urllib.request

import testlib
from testlib import check

testlib.skip_without_egl()
HERE = os.path.dirname(os.path.abspath(__file__))
DEMO = os.path.join(HERE, "..", "..", "tools", "demo")
tmp = tempfile.mkdtemp(prefix="shadebench-demo-")

with socket.socket() as s:
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
job = os.path.join(tmp, "small.json")
with open(job, "w") as f:
    json.dump({"technique": "forward", "frames": 20, "warmup_frames": 0,
               "scene": {"width": 64, "height": 48, "sphere_segments": 8}}, f)
state = os.path.join(tmp, "state")
env = dict(os.environ, SETUP="0", SHADEBENCH_SERVER="http://127.0.0.1:%d" % port, STATE_DIR=state,
           SHADEBENCHD=os.path.abspath(testlib.SHADEBENCHD), DEMO_JOBS=job)
pid_file = os.path.join(state, "shadebenchd.pid")
try:
    out = subprocess.run(["sh", DEMO], capture_output=True, text=True, env=env,
                         timeout=300 * testlib.TIME_SCALE)
    log = out.stdout + out.stderr
    check(out.returncode == 0 and "starting shadebenchd on 127.0.0.1:%d" % port in log,
          "the daemon is started at the URL's port: rc %d %s" % (out.returncode, log[-800:]))
    try:
        with urllib.request.urlopen("http://127.0.0.1:%d/healthz" % port, timeout=10) as r:
            up = r.status == 200
    except OSError:
        up = False
    check(up, "and answers there after the demo")
    progress = re.findall(r"^  \S+: (\d+)/20 frames \(\d+%\), (\w+)", log, re.M)
    check(progress and re.search(r"^  forward: 20 frames in [0-9.]+ s", log, re.M),
          "progress lines while the job runs, then its figures: %s" % log[-800:])
    # A remote server is never started here.
    remote = subprocess.run(["sh", DEMO], capture_output=True, text=True,
                            env=dict(env, SHADEBENCH_SERVER="http://192.0.2.1:%d" % port),
                            timeout=120 * testlib.TIME_SCALE)
    check(remote.returncode != 0 and "only on this machine" in remote.stderr,
          "a remote URL without a daemon is refused, not started here: %s" % remote.stderr[-300:])
finally:
    try:
        with open(pid_file) as f:
            os.kill(int(f.read().strip()), signal.SIGTERM)
        time.sleep(0.5)
    except (OSError, ValueError):
        pass
testlib.finish("e2e_demo")
