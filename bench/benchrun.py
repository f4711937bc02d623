"""What every bench script prints about the run itself, so that a figure
copied into the docs carries where it came from: the commit, the exact
command, the date, and the load the machine was under (/proc/loadavg at the
start and the end, and the jobs' own `result.interference`: the 1-minute
load when each job's timed region began and the share of the CPUs other
processes took during it)."""

import argparse
import datetime
import json
import os
import shlex
import statistics
import subprocess
import sys

_ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
# The end-to-end tests' helpers (a daemon on a free port, its jobs), which
# every bench drives the daemon with: `from benchrun import testlib`.
sys.path.insert(0, os.path.join(_ROOT, "tests", "e2e"))
import testlib  # noqa: E402,F401


def parser():
    """The bench's argument parser, its help the script's own docstring."""
    return argparse.ArgumentParser(description=sys.modules["__main__"].__doc__,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)


def write_json(path, value, **kw):
    """Writes value to path (--json) when one was given."""
    if path:
        with open(path, "w") as f:
            json.dump(value, f, **kw)


def _loadavg():
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def _commit():
    try:
        head = subprocess.run(["git", "-C", _ROOT, "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True, check=True).stdout.strip()
        # What the figures depend on: the code, the build and the benches (not the docs).
        dirty = subprocess.run(["git", "-C", _ROOT, "status", "--porcelain", "--untracked-files=no",
                                "--", "daemon", "client", "common", "shaders", "bench", "tests",
                                "configure.ac", "Makefile.am"],
                               capture_output=True, text=True, check=True).stdout.strip()
        return head + (" (with uncommitted changes)" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def cpu_work_ms(r):
    """CPU milliseconds all the daemon's threads took per timed frame
    (result.interference): on llvmpipe, where all the work is on the CPU, the
    cost that other processes' load inflates least."""
    i = r.get("interference", {})
    return i.get("daemon_cpu_share", 0) * i.get("cpus", 1) * i.get("interval_s", 0) * 1e3 / r["frames"]


class Run:
    """Call start() before the first job and end(results) after the last."""

    def start(self):
        self.t0 = datetime.datetime.now(datetime.timezone.utc)
        self.load0 = _loadavg()
        env = " ".join("%s=%s" % (k, os.environ[k]) for k in
                       ("SHADEBENCHD", "SHADEBENCH_COMPARE", "SHADEBENCH_CLIENT", "PNG_TOOL")
                       if k in os.environ)
        print("run: %s, commit %s, %d CPUs" % (self.t0.strftime("%Y-%m-%d %H:%M UTC"), _commit(),
                                                os.cpu_count()))
        print("command: %s%s" % (env + " " if env else "",
                                 " ".join(shlex.quote(a) for a in [os.path.relpath(sys.argv[0], _ROOT)]
                                          + sys.argv[1:])))
        print("load average (1, 5, 15 min) at the start: %s" % self.load0, flush=True)

    def end(self, results):
        """results: every job result of the run (dicts with `interference`)."""
        secs = (datetime.datetime.now(datetime.timezone.utc) - self.t0).total_seconds()
        print("\nload average (1, 5, 15 min) at the start: %s, at the end: %s; ran in %.0f s"
              % (self.load0, _loadavg(), secs))
        inter = [r["interference"] for r in results if isinstance(r, dict) and "interference" in r]
        if inter:
            loads = [i["loadavg_start"][0] for i in inter]
            other = [i.get("other_cpu_share", 0.0) for i in inter]
            print("jobs' interference: 1-minute load at their start %.1f to %.1f (median %.1f); "
                  "other processes' share of the CPUs in the timed regions: median %.0f %%, max %.0f %%; "
                  "%d of %d jobs flagged noisy"
                  % (min(loads), max(loads), statistics.median(loads), 100 * statistics.median(other),
                     100 * max(other), sum(1 for i in inter if i.get("noisy")), len(inter)))
