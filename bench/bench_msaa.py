#!/usr/bin/env python3
"""MSAA's cost (issue 22): frame time against the MSAA level for every
technique at 16, 256 and 1,024 lights on the `lights` preset, in one run on
one daemon, interleaved (each round runs every technique at every level,
A, B, A, B, so that load spreads evenly over them). Prints, per light count,
technique and level: the median frame_ms and cpu_work_ms (the CPU time all
the daemon's threads took per timed frame: on llvmpipe, which does all its
work on the CPU, the figure load does not move) with their ratios to the
same technique at msaa 1; the per-pass medians that show where MSAA costs
(the deferred family's edges and lighting, the harness's msaa_resolve);
the pixels the deferred family shades per sample; the bytes of render
targets the run took from the pool (result.msaa.targets_bytes_in_use); and
the load the run ran under (load averages, other processes' CPU share).

  bench/bench_msaa.py [--counts 16,256,1024] [--levels 1,2,4] [--techniques a,b,...]
      [--frames N] [--warmup N] [--repeat R] [--width W --height H] [--json FILE]

Levels above the device's limit (/v1/info device.caps.max_msaa) are left
out and said so. On llvmpipe GL_TIME_ELAPSED covers rasterisation only, so
frame_ms (and cpu_work_ms) compare techniques there; on a GPU gpu_ms does."""

import json
import statistics
import sys
import time

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--counts", default="16,256,1024")
ap.add_argument("--levels", default="1,2,4,8")
ap.add_argument("--techniques", default="", help="default: every registered technique")
ap.add_argument("--frames", type=int, default=4)
ap.add_argument("--warmup", type=int, default=1)
ap.add_argument("--repeat", type=int, default=2)
ap.add_argument("--width", type=int, default=480)
ap.add_argument("--height", type=int, default=320)
ap.add_argument("--json", help="write every result here")
args = ap.parse_args()


cpu_work_ms = benchrun.cpu_work_ms


def med(xs):
    return statistics.median(xs) if xs else float("nan")


bench = benchrun.Run()
bench.start()
d = testlib.Daemon()
runs = {}
loads = []
t_start = time.time()
try:
    info = d.json("GET", "/v1/info")[1]
    dev = info["device"]
    limit = dev.get("caps", {}).get("max_msaa", 1)
    levels = [int(x) for x in args.levels.split(",")]
    dropped = [m for m in levels if m > limit]
    levels = [m for m in levels if m <= limit]
    techs = ([t for t in args.techniques.split(",") if t] or
             [t["name"] if isinstance(t, dict) else t for t in info["techniques"]])
    counts = [int(c) for c in args.counts.split(",")]
    print("device: %s | %s | max_msaa %d%s" % (dev["gl_renderer"], dev["gl_version"], limit,
          " (left out: msaa %s)" % dropped if dropped else ""))
    print("scene: lights preset %dx%d, %d timed frames after %d warm-up, %d interleaved rounds"
          % (args.width, args.height, args.frames, args.warmup, args.repeat), flush=True)
    for rep in range(args.repeat):
        for n in counts:
            for tech in techs:
                for m in levels:
                    job = {"technique": tech, "frames": args.frames, "warmup_frames": args.warmup,
                           "msaa": m, "scene": {"preset": "lights", "lights": n,
                                                "width": args.width, "height": args.height}}
                    t0 = time.time()
                    done = d.run(job)
                    if done.get("status") != "done":
                        sys.exit("%s msaa %d, %d lights failed: %s" % (tech, m, n, done.get("error")))
                    r = done["result"]
                    runs.setdefault((n, tech, m), []).append(r)
                    i = r.get("interference", {})
                    loads.append((i.get("loadavg_start", [0])[0], i.get("other_cpu_share", 0)))
                    print("  [%d/%d] %5d lights %-20s msaa %d: frame %9.2f ms (%.0f s)"
                          % (rep + 1, args.repeat, n, tech, m, r["frame_ms"]["median"],
                             time.time() - t0), flush=True)

    print("\n| lights | technique | msaa | frame_ms | / msaa 1 | cpu_work_ms | / msaa 1 | "
          "passes (median ms) | edge pixels (share) | targets MiB |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for n in counts:
        for tech in techs:
            base = None
            for m in levels:
                rs = runs.get((n, tech, m), [])
                f = med([r["frame_ms"]["median"] for r in rs])
                c = med([cpu_work_ms(r) for r in rs])
                if m == levels[0]:
                    base = (f, c)
                sections = {}
                for r in rs:
                    for p, s in r.get("gpu_sections_ms", {}).items():
                        sections.setdefault(p, []).append(s.get("median", 0))
                passes = ", ".join("%s %.2f" % (p, med(v)) for p, v in sections.items()
                                   if p != "resolve")
                g = rs[-1].get(tech, {}).get("gbuffer", {}).get("msaa", {}) if rs else {}
                e = g.get("edge_pixels")
                edges = "%.0f (%.1f%%)" % (e["mean"], 100 * e["fraction_mean"]) if e else ""
                mib = med([r.get("msaa", {}).get("targets_bytes_in_use", 0) for r in rs]) / 1048576
                print("| %s | %s | %d | %.1f | %.2f | %.1f | %.2f | %s | %s | %.1f |"
                      % ("{:,}".format(n), tech, m, f, f / base[0], c, c / base[1], passes, edges,
                         mib))
    la = [x[0] for x in loads]
    oc = [x[1] for x in loads]
    bench.end([r for rs in runs.values() for r in rs])
    print("load: 1-minute load average %.1f to %.1f (median %.1f), other processes' CPU share "
          "%.2f to %.2f (median %.2f); %d jobs in %.0f s"
          % (min(la), max(la), med(la), min(oc), max(oc), med(oc), len(loads),
             time.time() - t_start))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"device": dev, "levels": levels, "counts": counts, "techniques": techs,
                       "runs": [{"lights": k[0], "technique": k[1], "msaa": k[2], "results": v}
                                for k, v in runs.items()]}, f)
finally:
    d.stop()
    d.cleanup()
