#!/usr/bin/env python3
"""The fleet's scale on a one-node Slurm cluster started here (the tests'
tests/e2e/slurmlib.py; needs root and tools/setup's slurm-wlm and munge):
a sweep of --points tiny points run on --classes device classes (node
features of the one node) by `shadebench sweep --slurm`, that is
points x classes array tasks. Prints the time to plan and submit, the time
the arrays took, the time to gather, and gathering again alone (the
gathering of a finished fleet folder, over all its task folders), and
checks that every task's result was gathered.

    sudo bench/bench_fleet.py --points 250 --classes 4      # 1,000 tasks

With --sweep FILE --devices A,B it runs that sweep instead, on device
classes (node features) named A and B, and prints the device comparison:

    sudo bench/bench_fleet.py --sweep examples/sweep-lights-techniques.json \
        --devices a100,mi210
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "e2e"))
sys.path.insert(0, HERE)
import benchrun  # noqa: E402
import slurmlib  # noqa: E402

BUILD = os.path.join(HERE, "..", "build")
CLIENT = os.environ.get("SHADEBENCH_CLIENT", os.path.join(BUILD, "shadebench"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--points", type=int, default=250, help="points of the sweep (at most 256)")
    ap.add_argument("--classes", type=int, default=4, help="device classes (node features)")
    ap.add_argument("--sweep", help="run this sweep file instead of tiny points")
    ap.add_argument("--devices", help="device class names for the node features (A,B,...)")
    ap.add_argument("--keep", action="store_true", help="keep the fleet folder")
    a = ap.parse_args()
    why = slurmlib.missing_requirements()
    if why:
        sys.exit("bench_fleet: " + why)
    run = benchrun.Run()
    run.start()
    slurmlib.FEATURES = (tuple(a.devices.split(",")) if a.devices else
                         tuple("class_%d" % i for i in range(a.classes)))
    tmp = tempfile.mkdtemp(prefix="shadebench-bench-fleet-")
    cluster = slurmlib.Cluster()
    try:
        # Tiny points: the figures are about Slurm and the client, not rendering.
        sweep = {"base": {"technique": "forward", "frames": 1, "warmup_frames": 0,
                          "scene": {"width": 16, "height": 16, "lights": 1}},
                 "vary": {"scene.light_speed": [round(0.01 * i, 2) for i in range(a.points)]}}
        path = os.path.join(tmp, "sweep.json")
        if a.sweep:
            shutil.copy(a.sweep, path)
            sweep = json.load(open(path))
        with open(path, "w") as f:
            json.dump(sweep, f)
        fleet = os.path.join(tmp, "fleet")
        t0 = time.time()
        r = subprocess.run([CLIENT, "sweep", path, "--slurm", "--devices",
                            ",".join(slurmlib.FEATURES), "--out", fleet],
                           env=cluster.env, capture_output=True, text=True)
        total = time.time() - t0
        out = r.stderr
        if r.returncode != 0:
            print(out[-3000:])
            sys.exit("bench_fleet: the sweep failed (exit %d)" % r.returncode)
        t1 = time.time()
        r2 = subprocess.run([CLIENT, "gather", fleet, "--out", os.path.join(tmp, "again"),
                             "--quiet"], env=cluster.env, capture_output=True, text=True)
        regather = time.time() - t1
        gathered = json.load(open(os.path.join(fleet, "sweep.json")))
        npoints = gathered["progress"]["points_total"] // len(slurmlib.FEATURES)
        print("\n%d points x %d device classes = %d array tasks on one node (%d CPUs)"
              % (npoints, len(slurmlib.FEATURES), npoints * len(slurmlib.FEATURES),
                 os.cpu_count()))
        print("gathered: %s of %s, status %s" % (gathered["progress"]["points_done"],
                                                  gathered["progress"]["points_total"],
                                                  gathered["status"]))
        print("sweep --slurm in all: %.1f s" % total)
        for line in out.splitlines():
            if re.search(r"submitted|arrays took|gathered in", line):
                print("  client: " + line.split("shadebench: ", 1)[-1])
        print("gather again, alone: %.2f s (exit %d)" % (regather, r2.returncode))
        if a.sweep:
            print("\n$ shadebench compare-devices DIR\n" + r.stdout)
    finally:
        cluster.stop()
        if not a.keep:
            shutil.rmtree(tmp, ignore_errors=True)
    run.end([])


if __name__ == "__main__":
    main()
