#!/usr/bin/env python3
"""OSL's options against forward on the thesis grid (issue 25): forward,
OSL with whole tiles ("all", the thesis's shading), with visibility "seen"
(the default), seen with a reshade budget (osl.budget_texels), seen with
lighting-change detection (osl.change_threshold), and seen with both, at
async distance 1, 5, 20 and 60, with moving and with still lights, auto
tiles (plus the thesis's own OSL, 256 texels and whole tiles, at d 20 with
moving lights), in one run on one daemon, interleaved (each round runs every
configuration, so that load spreads evenly over them). Prints per
configuration: the median frame_ms and its ratio to forward's in the same
round (the median of the per-round ratios), cpu_work_ms (the CPU time all
the daemon's threads took per timed frame: what load moves least on
llvmpipe), the lighting and raster passes' medians (which pass is the
cost), texels shaded per frame and per pixel on screen, the frame times'
spread (p99 / median), stale blocks (blocks read with other shading
than scheduled, visibility "seen" only), the staleness of the blocks read
(frames since the lights of their shading: median, p95, max), budget
overflows and reshades saved by change detection. With --quality, each
configuration at d 20 with moving lights runs once more against forward
(reference: forward) and its worst SSIM is printed.

  bench/bench_osl.py [--distances 1,5,20,60] [--frames N] [--warmup N] [--repeat R]
      [--width W --height H] [--budget TEXELS] [--threshold T] [--quality] [--json FILE]
      [--svg FILE]
  bench/bench_osl.py --chart RESULTS.txt --svg FILE   # the chart again from a run's output

The chart (standard library only) draws OSL's frame time over forward's
against async distance, moving lights, one line per configuration, on a
log scale, beside the thesis's own factors (dynamic scene, GPUs, d 20:
5.12, 11.27 and 11.75; chapter 4.1).

On llvmpipe GL_TIME_ELAPSED covers rasterisation only, so frame_ms (and
cpu_work_ms) compare techniques there; on a GPU gpu_ms does."""

import os
import statistics
import sys

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--distances", default="1,5,20,60")
ap.add_argument("--frames", type=int, default=20)
ap.add_argument("--warmup", type=int, default=3)
ap.add_argument("--repeat", type=int, default=3)
ap.add_argument("--width", type=int, default=1080)
ap.add_argument("--height", type=int, default=720)
ap.add_argument("--budget", type=int, default=196608, help="osl.budget_texels of the budget rows")
ap.add_argument("--threshold", type=float, default=0.02, help="osl.change_threshold of the change rows")
ap.add_argument("--quality", action="store_true", help="SSIM against forward at d 20, moving lights")
ap.add_argument("--temporal", type=int, default=0,
                help="with --quality: also the flicker over this many frames at the capture")
ap.add_argument("--json", help="write every result here")
ap.add_argument("--svg", help="chart file")
ap.add_argument("--chart", help="only draw the chart, from this output of an earlier run")
args = ap.parse_args()

# The thesis's OSLProg / ForwardProg factors, dynamic scene (d 20, 256
# texels, whole tiles), on its three GPUs (chapter 4.1).
THESIS_DYNAMIC = (5.12, 11.27, 11.75)


def chart(series, path, title):
    """series: {label: {distance: ratio to forward}}; log-scale y."""
    import math
    W, H, L, R, T, B = 720, 440, 60, 200, 30, 50
    dists = sorted({d for pts in series.values() for d in pts})
    ys = [v for pts in series.values() for v in pts.values() if v > 0] + list(THESIS_DYNAMIC) + [1.0]
    y0, y1 = math.floor(math.log10(min(ys))), math.ceil(math.log10(max(ys)))

    def px(d):
        return L + (dists.index(d) + 0.5) / len(dists) * (W - L - R)

    def py(v):
        return H - B - (math.log10(v) - y0) / (y1 - y0) * (H - T - B)
    colours = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2"]
    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="sans-serif" '
           'font-size="12"><rect width="100%%" height="100%%" fill="white"/>' % (W, H)]
    for e in range(y0, y1 + 1):
        for m in (1, 2, 5):
            v = m * 10 ** e
            if 10 ** y0 <= v <= 10 ** y1:
                out.append('<line x1="%d" x2="%d" y1="%.1f" y2="%.1f" stroke="#%s"/><text x="%d" '
                           'y="%.1f" text-anchor="end">%g</text>' % (L, W - R, py(v), py(v),
                                                                     "999" if v == 1 else "e4e4e4",
                                                                     L - 5, py(v) + 4, v))
    out.append('<text x="%d" y="%.1f" fill="#555">forward</text>' % (W - R - 50, py(1.0) - 4))
    for d in dists:
        out.append('<text x="%.1f" y="%d" text-anchor="middle">%g</text>' % (px(d), H - B + 18, d))
    out.append('<text x="%d" y="%d" text-anchor="middle">async distance</text>'
               % ((L + W - R) / 2, H - 12))
    names = {"all": "whole tiles (auto)", "seen": "seen (the default)", "budget": "seen + budget",
             "change": "seen + change", "both": "seen + budget + change",
             "thesis": "thesis's OSL here (256)"}
    for k, (label, pts) in enumerate(series.items()):
        c = colours[k % len(colours)]
        xy = [(px(d), py(pts[d])) for d in dists if pts.get(d, 0) > 0]
        for (ax, ay), (bx, by) in zip(xy, xy[1:]):
            out.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="%s" stroke-width="2"/>'
                       % (ax, ay, bx, by, c))
        for ax, ay in xy:
            out.append('<circle cx="%.1f" cy="%.1f" r="3.5" fill="%s"/>' % (ax, ay, c))
        out.append('<line x1="%d" x2="%d" y1="%d" y2="%d" stroke="%s" stroke-width="2"/><text x="%d" '
                   'y="%d">%s</text>' % (W - R + 10, W - R + 30, T + 10 + 18 * k, T + 10 + 18 * k, c,
                                         W - R + 35, T + 14 + 18 * k, names.get(label, label)))
    if 20.0 in dists:
        k = len(series)
        for v in THESIS_DYNAMIC:
            out.append('<rect x="%.1f" y="%.1f" width="8" height="8" fill="none" stroke="black"/>'
                       % (px(20.0) + 8, py(v) - 4))
        out.append('<rect x="%d" y="%d" width="8" height="8" fill="none" stroke="black"/><text x="%d" '
                   'y="%d">the thesis, its 3 GPUs</text>' % (W - R + 16, T + 6 + 18 * k, W - R + 35,
                                                            T + 14 + 18 * k))
    out.append('<text x="%d" y="%d">%s</text>' % (L, T - 10, title))
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out))
    print("chart: %s" % path)


def series_from_text(path):
    """The moving-lights table of an earlier run's output."""
    series, on = {}, False
    for line in open(path):
        if line.startswith("moving lights:"):
            on = True
        elif line.startswith("still lights:"):
            on = False
        elif on and line.startswith("osl "):
            f = line.split()
            label, d = f[1], float(f[2].split("=")[1])
            series.setdefault(label, {})[d] = float(f[4])
    return series


if args.chart:
    if not args.svg:
        sys.exit("bench_osl: --chart needs --svg")
    chart(series_from_text(args.chart), args.svg,
          "OSL / forward frame time, moving lights (from %s)" % os.path.basename(args.chart))
    sys.exit(0)


cpu_work_ms = benchrun.cpu_work_ms


def med(xs):
    return statistics.median(xs) if xs else float("nan")


# (technique, async distance, label): the label names the OSL options.
OPTIONS = {
    "all": {"resolution": "auto", "visibility": "all"},
    "seen": {},  # the defaults: auto tiles, seen
    "budget": {"budget_texels": args.budget},
    "change": {"change_threshold": args.threshold},
    "both": {"budget_texels": args.budget, "change_threshold": args.threshold},
    "thesis": {"resolution": 256, "visibility": "all"},
}
DISTANCES = [float(x) for x in args.distances.split(",")]
configs = [("forward", None, None)]
for dist in DISTANCES:
    for label in ("all", "seen", "budget", "change", "both"):
        configs.append(("osl", dist, label))
if 20.0 in DISTANCES:
    configs.append(("osl", 20.0, "thesis"))


def runs_with(c, moving):
    """Still lights reshade nothing after the first frame: the budget and
    change detection have nothing to act on, and the thesis's 256 texels
    are measured with moving lights only."""
    return moving or c[2] in (None, "all", "seen")


def name(c):
    return "forward" if c[0] == "forward" else "osl %s d=%g" % (c[2], c[1])


def job_for(c, moving, frames, warmup):
    job = {"technique": c[0], "frames": frames, "warmup_frames": warmup,
           "scene": {"preset": "grid", "dynamic": moving, "width": args.width,
                     "height": args.height}}
    if c[0] == "osl":
        job["async_distance"] = c[1]
        job["osl"] = dict(OPTIONS[c[2]])
    return job


bench = benchrun.Run()
bench.start()
d = testlib.Daemon()
results = []
rows = {}
try:
    dev = d.json("GET", "/v1/info")[1]["device"]
    print("device: %s | %s" % (dev["gl_renderer"], dev["gl_version"]))
    print("scene: grid %dx%d, %d timed frames after %d warm-up, %d interleaved rounds, auto "
          "tiles; budget %d texels, change threshold %g" % (args.width, args.height, args.frames,
                                                            args.warmup, args.repeat, args.budget,
                                                            args.threshold), flush=True)
    for rep in range(args.repeat):
        for moving in (True, False):
            fwd_ms = None
            for c in configs:
                if not runs_with(c, moving):
                    continue
                job = job_for(c, moving, args.frames, args.warmup)
                done = d.run(job)
                if done.get("status") != "done":
                    sys.exit("bench_osl: %s failed: %s" % (name(c), done.get("error")))
                r = done["result"]
                results.append(r)
                ms = r["frame_ms"]["median"]
                if c[0] == "forward":
                    fwd_ms = ms
                row = rows.setdefault((moving, c), {"ms": [], "ratio": [], "cpu": [], "light": [],
                                                     "raster": [], "texels": [], "spread": [],
                                                     "stale": [], "age": [], "over": [],
                                                     "saved": []})
                row["ms"].append(ms)
                row["ratio"].append(ms / fwd_ms)
                row["cpu"].append(cpu_work_ms(r))
                sec = r.get("gpu_sections_ms", {})
                row["light"].append(sec.get("lighting", {}).get("median", 0.0))
                row["raster"].append(sec.get("raster", sec.get("shading", {})).get("median", 0.0))
                row["spread"].append(r["frame_ms"]["p99"] / ms)
                o = r.get("osl", {})
                row["texels"].append(o.get("texels_shaded_per_frame", {}).get("mean", 0.0))
                row["stale"].append(o.get("visibility", {}).get("stale_blocks", 0))
                st = o.get("staleness")
                row["age"].append((st["median"], st["p95"], st["max"]) if st else None)
                row["over"].append(o.get("budget", {}).get("overflow_frames", 0))
                row["saved"].append(o.get("change", {}).get("reshades_saved_per_frame", 0.0))
                print("  round %d %s %-20s frame_ms %8.2f (x%.2f of forward)"
                      % (rep + 1, "moving" if moving else "still ", name(c), ms, ms / fwd_ms),
                      flush=True)
    quality, flickers = {}, {}
    if args.quality and 20.0 in DISTANCES:
        for c in configs:
            if c[0] != "osl" or c[1] != 20.0:
                continue
            job = job_for(c, True, args.frames, args.warmup)
            job.update(reference="forward", capture_interval=args.frames)
            if args.temporal:
                job["temporal"] = {"frames": args.temporal}
            done = d.run(job)
            q = done.get("result", {}).get("quality", {})
            quality[c] = q.get("worst_ssim", {}).get("value")
            flicker = q.get("worst_flicker", {}).get("value")
            if flicker is not None:
                flickers[c] = flicker
            print("  quality %-20s worst SSIM against forward %s%s" % (
                name(c), quality[c], ", flicker %s" % flicker if flicker is not None else ""),
                flush=True)
finally:
    testlib.stop_and_check(d)

pixels = args.width * args.height
for moving in (True, False):
    print("\n%s lights: median over %d rounds" % ("moving" if moving else "still", args.repeat))
    print("%-20s %9s %6s %9s %9s %9s %12s %9s %8s %7s %11s %5s %6s" % (
        "configuration", "frame_ms", "/fwd", "cpu_work", "lighting", "raster", "texels/frame",
        "texels/px", "p99/med", "stale", "age m/95/mx", "over", "saved"))
    for c in configs:
        if (moving, c) not in rows:
            continue
        row = rows[(moving, c)]
        t = med(row["texels"])
        ages = [a for a in row["age"] if a]
        age = "%d/%d/%d" % tuple(max(a[k] for a in ages) for k in range(3)) if ages else "-"
        print("%-20s %9.2f %6.2f %9.2f %9.2f %9.2f %12.0f %9.3f %8.2f %7d %11s %5d %6.1f" % (
            name(c), med(row["ms"]), med(row["ratio"]), med(row["cpu"]), med(row["light"]),
            med(row["raster"]), t, t / pixels, med(row["spread"]), max(row["stale"]), age,
            max(row["over"]), med(row["saved"])))
if args.svg:
    series = {}
    for (moving, c), row in rows.items():
        if moving and c[0] == "osl":
            series.setdefault(c[2], {})[c[1]] = med(row["ratio"])
    chart(series, args.svg, "OSL / forward frame time, moving lights, grid %dx%d"
          % (args.width, args.height))
if quality:
    print("\nworst SSIM against forward, d 20, moving lights: " +
          ", ".join("%s %.5f" % (c[2], v) for c, v in quality.items() if v is not None))
if flickers:
    print("worst flicker against forward over %d frames, d 20, moving lights: " % args.temporal +
          ", ".join("%s %.5f" % (c[2], v) for c, v in flickers.items()))
bench.end(results)
benchrun.write_json(args.json, results)
