#!/usr/bin/env python3
"""OSL's flicker against its async distance (issue 22): OSL with moving
lights at each async distance, scored over `--temporal` consecutive frames
against forward (`"temporal": {"frames": K}`: the mean over frame pairs of
|(T_t - T_t-1) - (R_t - R_t-1)| on luma, docs/metrics.md#flicker), beside
its worst SSIM. Flicker and SSIM are pure functions of the frames, so one
job each, nothing interleaved. Prints a table and, with --svg FILE, draws
flicker against the async distance (one line per OSL resolution).

  bench/bench_flicker.py [--distances 0,1,2,4,8,16,32] [--resolutions auto,64]
      [--temporal 8] [--frames 8] [--width 320 --height 240] [--svg FILE] [--json FILE]"""

import sys

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--distances", default="0,1,2,4,8,16,32")
ap.add_argument("--resolutions", default="auto,64")
ap.add_argument("--temporal", type=int, default=8)
ap.add_argument("--frames", type=int, default=8)
ap.add_argument("--width", type=int, default=320)
ap.add_argument("--height", type=int, default=240)
ap.add_argument("--svg", help="write the chart here")
ap.add_argument("--json", help="write every figure here")
args = ap.parse_args()
distances = [int(x) for x in args.distances.split(",")]
resolutions = [r if r == "auto" else int(r) for r in args.resolutions.split(",")]


def svg_chart(series, path):
    """Flicker (y) against async distance (x, a linear scale), a polyline
    and labelled points per series; standard library only."""
    W, H, L, R, T, B = 640, 400, 80, 150, 40, 60
    xs = [x for pts in series.values() for x, _ in pts]
    ys = [y for pts in series.values() for _, y in pts]
    x0, x1 = min(xs), max(xs) or 1
    y1 = max(ys) * 1.1 or 1
    sx = lambda x: L + (x - x0) / (x1 - x0) * (W - L - R)  # noqa: E731
    sy = lambda y: H - B - y / y1 * (H - T - B)  # noqa: E731
    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="DejaVu Sans" '
           'font-size="12">' % (W, H), '<rect width="100%" height="100%" fill="white"/>',
           '<text x="%d" y="22" font-size="14">OSL flicker against forward, moving lights, %dx%d, '
           '%d frames a run</text>' % (L, args.width, args.height, args.temporal)]
    out.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="black"/>' % (L, H - B, W - R, H - B))
    out.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="black"/>' % (L, T, L, H - B))
    for x in sorted(set(xs)):
        out.append('<text x="%.1f" y="%d" text-anchor="middle">%d</text>' % (sx(x), H - B + 16, x))
    for i in range(6):
        y = y1 * i / 5
        out.append('<text x="%d" y="%.1f" text-anchor="end">%.5f</text>' % (L - 6, sy(y) + 4, y))
        out.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#ddd"/>' % (L, sy(y), W - R, sy(y)))
    out.append('<text x="%d" y="%d" text-anchor="middle">osl.async_distance</text>'
               % ((L + W - R) // 2, H - 18))
    out.append('<text x="16" y="%d" transform="rotate(-90 16 %d)" text-anchor="middle">flicker '
               '(mean |dT - dR| on luma)</text>' % ((T + H - B) // 2, (T + H - B) // 2))
    colours = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd"]
    for i, (name, pts) in enumerate(series.items()):
        c = colours[i % len(colours)]
        out.append('<polyline fill="none" stroke="%s" stroke-width="2" points="%s"/>'
                   % (c, " ".join("%.1f,%.1f" % (sx(x), sy(y)) for x, y in pts)))
        for x, y in pts:
            out.append('<circle cx="%.1f" cy="%.1f" r="3" fill="%s"/>' % (sx(x), sy(y), c))
        out.append('<text x="%d" y="%d" fill="%s">%s</text>' % (W - R + 10, T + 18 * (i + 1), c, name))
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


bench = benchrun.Run()
bench.start()
d = testlib.Daemon()
figures = {}
try:
    for res in resolutions:
        for dist in distances:
            job = {"technique": "osl", "frames": args.frames, "warmup_frames": 1,
                   "capture_interval": args.frames, "reference": "forward",
                   "temporal": {"frames": args.temporal}, "metrics": ["ssim"],
                   "osl": {"async_distance": dist, "resolution": res},
                   "scene": {"preset": "grid", "width": args.width, "height": args.height,
                             "dynamic": True}}
            done = d.run(job)
            if done.get("status") != "done":
                sys.exit("osl %s d %d failed: %s" % (res, dist, done.get("error")))
            q = done["result"]["quality"]
            figures[(str(res), dist)] = (q["worst_flicker"]["value"], q["worst_ssim"]["value"])
            print("  osl %-4s d %2d: flicker %.6f  worst SSIM %.5f"
                  % (res, dist, *figures[(str(res), dist)]), flush=True)
finally:
    testlib.stop_and_check(d)

print("\n| async distance | " + " | ".join("OSL %s flicker | SSIM" % r for r in resolutions) + " |")
print("|---|" + "---|---|" * len(resolutions))
for dist in distances:
    print("| %d | " % dist + " | ".join("%.6f | %.5f" % figures[(str(r), dist)] for r in resolutions) + " |")
if args.svg:
    svg_chart({"OSL %s" % r: [(dist, figures[(str(r), dist)][0]) for dist in distances]
               for r in resolutions}, args.svg)
    print("chart: %s" % args.svg)
benchrun.write_json(args.json, {"%s/%d" % k: {"flicker": v[0], "ssim": v[1]} for k, v in figures.items()},
                    indent=1)
bench.end([])
