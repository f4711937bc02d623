#!/usr/bin/env python3
"""The many-lights family against light count: every light-culling
technique with `forward` and `unlit` as anchors, on the `lights` preset (or
on a glTF asset with --asset, its generated lights placed in its bounds), in
one run on one daemon, interleaved across repeats. Prints frame_ms medians,
ratios to forward and to unlit, where each technique's binning stands, the
overflow counters, the crossover points ("from N lights on, X beats Y") and
the issue's goals; writes a log-log chart (SVG) of frame time against light
count.

  bench/bench_lights_techniques.py [--counts 16,64,256,1024,4096,16384]
      [--frames N] [--warmup N] [--repeat R] [--width W --height H]
      [--forward-max N] [--techniques a,b,...] [--variant NAME=TECH:JSON ...]
      [--svg FILE] [--json FILE] [--asset FILE.glb]

--variant names a technique with options, usable in --techniques: e.g.
--variant 'td8=tiled_deferred:{"tile_size": 8}' --techniques unlit,td8,...
(tiled_deferred_cpu is built in: tiled deferred with CPU binning).

Forward walks every light for every fragment: on llvmpipe at 1080x720 it
takes about 10 s a frame at 1,024 lights and 40 s at 4,096. Above
--forward-max (default 1,024) it is not run; its frame time there is
extrapolated linearly from its two largest measured counts and marked "~"
(forward's cost is linear in the light count: see bench_lights.py).

On llvmpipe compute shaders run on the calling thread, outside
GL_TIME_ELAPSED, so frame_ms is the figure to compare and a technique's
binning share is binning_cpu_ms / frame_ms (the CPU time of its binning
pass; for tiles it includes the wait for the depth the pass reads).

On a shared machine frame_ms also measures the other processes: each row
shows cpu_work_ms as well, the CPU time all the daemon's threads took per
timed frame (result.interference: daemon_cpu_share x cpus x interval), which
on llvmpipe (all work on the CPU) is the technique's cost whatever the
load; crossovers and goals are computed on both.

Interleaved: each repeat runs every technique at every count in turn
(A, B, A, B over --repeat rounds, default 2); figures are medians over the
repeats of the job medians and ratios are ratios of those medians. The
run's commit, command, date and load (/proc/loadavg at the start and the
end, and the jobs' result.interference) are printed with them."""

import json
import math
import os
import statistics
import sys
import time

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--counts", default="16,64,256,1024,4096,16384")
ap.add_argument("--techniques", default="unlit,forward,deferred,tiled_deferred,tiled_deferred_cpu,"
                "forward_plus,clustered_forward,clustered_deferred")
ap.add_argument("--frames", type=int, default=4, help="timed frames up to 1,024 lights")
ap.add_argument("--frames-high", type=int, default=2, help="timed frames above 1,024 lights")
ap.add_argument("--warmup", type=int, default=1)
ap.add_argument("--repeat", type=int, default=2)
ap.add_argument("--width", type=int, default=1080)
ap.add_argument("--height", type=int, default=720)
ap.add_argument("--forward-max", type=int, default=1024, help="largest count forward runs at")
ap.add_argument("--svg", default="bench-lights-techniques.svg", help="chart file ('' for none)")
ap.add_argument("--variant", action="append", default=[],
                help="NAME=TECHNIQUE:JSON, a technique with options (repeatable)")
ap.add_argument("--json", help="write every result here")
ap.add_argument("--from-json", help="report on the results a --json run wrote, without running")
ap.add_argument("--asset", help="a .glb or .gltf: uploaded to the daemon and rendered instead of the "
                "lights preset, with --counts generated point lights in its bounds (its own lights off)")
args = ap.parse_args()

counts = [int(c) for c in args.counts.split(",")]
names = args.techniques.split(",")
# Variants by name: technique and its options.
VARIANTS = {"tiled_deferred_cpu": ("tiled_deferred", {"binning": "cpu"})}
for v in args.variant:
    vname, _, rest = v.partition("=")
    vtech, _, vopts = rest.partition(":")
    if not vname or not vtech:
        sys.exit("--variant %r: expected NAME=TECHNIQUE:JSON" % v)
    VARIANTS[vname] = (vtech, json.loads(vopts) if vopts else None)


ASSET_NAME = os.path.basename(args.asset) if args.asset else None
SCENE = {"asset": ASSET_NAME, "asset_lights": False} if args.asset else {"preset": "lights"}
SCENE_LABEL = "asset %s" % ASSET_NAME if args.asset else "lights preset"


def job_for(name, n):
    tech, opts = VARIANTS.get(name, (name, None))
    job = {"technique": tech, "frames": args.frames if n <= 1024 else args.frames_high,
           "warmup_frames": args.warmup,
           "capture_interval": 0,
           "scene": dict(SCENE, lights=n, width=args.width, height=args.height)}
    if opts:
        job[tech] = opts
    return job


def runs(name, n):
    return name != "forward" or n <= args.forward_max


results = {(t, n): [] for t in names for n in counts}
if args.from_json:
    with open(args.from_json) as f:
        for key, rs in json.load(f).items():
            t, n = key.rsplit("@", 1)
            if (t, int(n)) in results:
                results[(t, int(n))] = rs
started = time.time()
bench = benchrun.Run()
d = None if args.from_json else testlib.Daemon()
try:
    info = d.json("GET", "/v1/info")[1]["device"] if d else \
        next(iter(rs[0] for rs in results.values() if rs))["device"]
    print("device: %s | %s | %s" % (info["gl_renderer"], info["gl_version"], info["egl_device"]))
    if d and args.asset:
        with open(args.asset, "rb") as f:
            body = f.read()
        t0 = time.time()
        status, up = d.json("PUT", "/v1/assets/" + ASSET_NAME, body, timeout=600)
        if status not in (200, 201):
            sys.exit("uploading %s: %d %s" % (args.asset, status, up))
        desc = up.get("description", {})
        print("asset: %s, %d bytes, %d triangles, %d textures, uploaded and converted in %.2f s"
              % (ASSET_NAME, len(body), desc.get("triangles", 0), len(desc.get("textures", [])),
                 time.time() - t0))
    print("scene: " + SCENE_LABEL + " %dx%d, %d (%d above 1,024 lights) timed frames after %d warm-up, "
          "%d repeat(s); "
          "forward up to %d lights" % (args.width, args.height, args.frames, args.frames_high,
                                      args.warmup, args.repeat, args.forward_max))
    if d:
        bench.start()
    print()
    for rep in range(0 if args.from_json else args.repeat):
        for n in counts:
            for t in names:
                if not runs(t, n):
                    continue
                t0 = time.time()
                done = d.wait(d.submit(job_for(t, n)), timeout=7200)
                if done.get("status") != "done":
                    sys.exit("%s at %d lights failed: %s" % (t, n, done.get("error")))
                r = done["result"]
                results[(t, n)].append(r)
                print("  [%d/%d] %-20s %6d lights  frame %10.2f ms  (%.0f s)"
                      % (rep + 1, args.repeat, t, n, r["frame_ms"]["median"], time.time() - t0),
                      flush=True)
finally:
    if d:
        d.stop()
        d.cleanup()
if d:
    bench.end([r for rs in results.values() for r in rs])
if args.json and not args.from_json:  # before the report, so that a report's failure loses nothing
    with open(args.json, "w") as f:
        json.dump({"%s@%d" % k: v for k, v in results.items()}, f)


work_ms = benchrun.cpu_work_ms


def med(t, n, series="frame_ms"):
    rs = results.get((t, n))
    if not rs:
        return None
    if series == "work":
        return statistics.median(work_ms(r) for r in rs)
    return statistics.median(r[series]["median"] for r in rs)


SERIES = "frame_ms"


def frame(t, n, series=None):
    """(figure, extrapolated?) for technique t at n lights, in SERIES."""
    series = series or SERIES
    m = med(t, n, series)
    if m is not None:
        return m, False
    done = [c for c in counts if med(t, c) is not None]
    if len(done) < 2:
        return None, False
    a, b = done[-2], done[-1]
    slope = (med(t, b, series) - med(t, a, series)) / (b - a)
    return med(t, b, series) + slope * (n - b), True


def desc(t, n, *path):
    """Median of a describe() figure over the runs (technique's own object)."""
    tech = VARIANTS.get(t, (t, None))[0]
    vals = []
    for r in results[(t, n)]:
        v = r.get(tech, {})
        for p in path:
            v = v.get(p, {}) if isinstance(v, dict) else {}
        if isinstance(v, (int, float)):
            vals.append(v)
    return statistics.median(vals) if vals else None


def fmt(v, approx=False):
    if v is None:
        return "-"
    s = "%.1f" % v if v >= 10 else "%.2f" % v
    return ("~" if approx else "") + s


loads = [r["interference"]["loadavg_start"][0] for rs in results.values() for r in rs
         if "interference" in r]
if loads:
    print("load average over the jobs: %.1f to %.1f (%d CPUs)"
          % (min(loads), max(loads), next(iter(results.values()))[0]["interference"]["cpus"]
             if next(iter(results.values())) else 0))
print("\n| lights | technique | frame_ms | / forward | / unlit | cpu_work_ms | / forward | / unlit "
      "| binning ms (share) | lights per cell (fullest) | overflowed cells per frame |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for n in counts:
    fw, fw_x = frame("forward", n)
    ul, _ = frame("unlit", n)
    wfw, wfw_x = frame("forward", n, "work")
    wul, _ = frame("unlit", n, "work")
    for t in names:
        f, x = frame(t, n)
        w, wx = frame(t, n, "work")
        if f is None:
            continue
        binning = desc(t, n, "binning_cpu_ms", "median")
        share = "%s (%.1f%%)" % (fmt(binning), 100 * binning / f) if binning is not None else "-"
        lpc = desc(t, n, "lights_per_cell", "mean")
        full = desc(t, n, "lights_per_cell", "fullest", "max")
        cells = "%.1f (%d)" % (lpc, full) if lpc is not None else "-"
        ov = desc(t, n, "overflow", "cells_per_frame", "max")
        print("| %d | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |"
              % (n, t, fmt(f, x), fmt(f / fw, x or fw_x) if fw else "-",
                 fmt(f / ul) if ul else "-", fmt(w, wx), fmt(w / wfw, wx or wfw_x) if wfw else "-",
                 fmt(w / wul) if wul else "-", share, cells, "-" if ov is None else "%d" % ov))

def goal(label, value, target, ok):
    print("  %-62s %s (goal %s): %s" % (label, value, target, "met" if ok else "MISSED"))


def report(series):
    global SERIES
    SERIES = series
    # Crossovers: where the ratio t_X / t_Y crosses 1, interpolated in log-log
    # between the two measured counts around it (extrapolated forward marked).
    print("\nCrossovers (from N lights on, X beats Y; N interpolated in log-log):")
    for i, x in enumerate(names):
        for y in names[i + 1:]:
            if "unlit" in (x, y):
                continue
            pts = [(n,) + frame(x, n) + frame(y, n) for n in counts]
            pts = [(n, fx, fy, ax or ay) for n, fx, ax, fy, ay in pts if fx and fy]
            if len(pts) < 2:
                continue
            sign = [fx < fy for _, fx, fy, _ in pts]
            if all(sign) or not any(sign):
                win = x if sign[0] else y
                print("  %s beats %s at every count measured (%d to %d)"
                      % (win, y if win == x else x, pts[0][0], pts[-1][0]))
                continue
            for k in range(1, len(pts)):
                if sign[k] != sign[k - 1]:
                    (n0, x0, y0, a0), (n1, x1, y1, a1) = pts[k - 1], pts[k]
                    r0, r1 = math.log(x0 / y0), math.log(x1 / y1)
                    cross = math.exp(math.log(n0) + (math.log(n1) - math.log(n0)) * r0 / (r0 - r1))
                    win, lose = (x, y) if sign[k] else (y, x)
                    print("  from ~%d lights on, %s beats %s (measured: %d -> %d)%s"
                          % (round(cross), win, lose, n0, n1,
                             " [forward extrapolated]" if a0 or a1 else ""))

    print("\nGoals (llvmpipe, 1080x720):")
    if 1024 in counts and "clustered_deferred" in names:
        cd, _ = frame("clustered_deferred", 1024)
        fw, fw_x = frame("forward", 1024)
        ul, _ = frame("unlit", 1024)
        if cd and fw:
            goal("clustered_deferred at 1,024 lights, speed-up over forward", "%.1fx" % (fw / cd),
                 ">= 20x", fw / cd >= 20)
        if cd and ul:
            goal("clustered_deferred at 1,024 lights, frame time / unlit", "%.1fx" % (cd / ul),
                 "<= 3x", cd / ul <= 3)
    if 4096 in counts and {"clustered_deferred", "tiled_deferred"} <= set(names):
        cd, _ = frame("clustered_deferred", 4096)
        td, _ = frame("tiled_deferred", 4096)
        if cd and td:
            print("  clustered_deferred against tiled_deferred at 4,096 lights: %.2fx faster "
                  "(Olsson et al. 2012: about 3.2x at about 2,400 lights, on a GPU)" % (td / cd))
    # binning_cpu_ms is wall time of the pass's calls: a share of frame_ms.
    for t in ("clustered_deferred", "clustered_forward", "tiled_deferred", "forward_plus"):
        if 4096 not in counts or t not in names or series != "frame_ms":
            continue
        f, _ = frame(t, 4096, "frame_ms")
        b = desc(t, 4096, "binning_cpu_ms", "median")
        if f and b is not None:
            goal("%s binning share of frame_ms at 4,096 lights" % t, "%.1f%%" % (100 * b / f),
                 "< 10%", b / f < 0.10)


for series in ("frame_ms", "work"):
    print("\n== on %s ==" % ("frame_ms" if series == "frame_ms" else "cpu_work_ms (CPU time per frame)"))
    report(series)

if args.svg:
    # A log-log chart of frame_ms, standard library only.
    SERIES = "frame_ms"
    W, H, L, R, T, B = 760, 480, 70, 190, 20, 50
    xs = [math.log10(n) for n in counts]
    ys = [math.log10(frame(t, n)[0]) for t in names for n in counts if frame(t, n)[0]]
    x0, x1 = min(xs), max(xs)
    y0, y1 = math.floor(min(ys)), math.ceil(max(ys))

    def px(n):
        return L + (math.log10(n) - x0) / (x1 - x0) * (W - L - R)

    def py(ms):
        return H - B - (math.log10(ms) - y0) / (y1 - y0) * (H - T - B)
    colours = ["#000000", "#d62728", "#1f77b4", "#2ca02c", "#98df8a", "#ff7f0e", "#9467bd",
               "#8c564b", "#e377c2"]
    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="sans-serif" '
           'font-size="12"><rect width="100%%" height="100%%" fill="white"/>' % (W, H)]
    for e in range(y0, y1 + 1):
        out.append('<line x1="%d" x2="%d" y1="%.1f" y2="%.1f" stroke="#ddd"/><text x="%d" y="%.1f" '
                   'text-anchor="end">%g ms</text>' % (L, W - R, py(10 ** e), py(10 ** e), L - 5,
                                                      py(10 ** e) + 4, 10 ** e))
    for n in counts:
        out.append('<text x="%.1f" y="%d" text-anchor="middle">%d</text>' % (px(n), H - B + 18, n))
    out.append('<text x="%d" y="%d" text-anchor="middle">lights (log)</text>' % ((L + W - R) / 2, H - 10))
    for k, t in enumerate(names):
        c = colours[k % len(colours)]
        pts = [(px(n), py(frame(t, n)[0]), frame(t, n)[1]) for n in counts if frame(t, n)[0]]
        for (ax, ay, _), (bx, by, bext) in zip(pts, pts[1:]):
            out.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="%s" stroke-width="2"%s/>'
                       % (ax, ay, bx, by, c, ' stroke-dasharray="5,4"' if bext else ""))
        for ax, ay, ext in pts:
            out.append('<circle cx="%.1f" cy="%.1f" r="3" fill="%s"/>' % (ax, ay, "white" if ext else c))
        out.append('<line x1="%d" x2="%d" y1="%d" y2="%d" stroke="%s" stroke-width="2"/><text x="%d" '
                   'y="%d">%s</text>' % (W - R + 10, W - R + 30, T + 10 + 18 * k, T + 10 + 18 * k, c,
                                         W - R + 35, T + 14 + 18 * k, t))
    out.append('<text x="%d" y="%d">frame_ms, %s %dx%d (dashed: extrapolated)</text>'
               % (L, T - 5 if T > 15 else 12, SCENE_LABEL, args.width, args.height))
    out.append("</svg>")
    with open(args.svg, "w") as f:
        f.write("\n".join(out))
    print("\nchart: %s" % args.svg)


