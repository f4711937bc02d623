#!/usr/bin/env python3
"""TAA against MSAA (issue 37): on forward and on clustered deferred, no
anti-aliasing, MSAA 2 and 4, and TAA (look.post taa, its defaults, and
with AABB clamping), each measured three ways on one daemon:

- cost: frame_ms (and cpu_work_ms, the CPU time the daemon took a frame:
  on llvmpipe, where all the work is on the CPU, what other processes'
  load inflates least) of --frames timed frames with an orbiting camera,
  medians over --repeat rounds in which every configuration runs once, in
  turn (interleaved), and the ratio to the same technique without
  anti-aliasing;
- accuracy: the captured frame's SSIM, FLIP and PSNR against forward
  supersampled 4 x 4 (box-filtered in linear light), on a still camera and
  on the orbit (a pure function of the frame: one job each);
- stability: flicker over --temporal frames in a row on the orbit (the
  temporal-difference error of quality/flicker.h, against the supersampled
  reference's own change) and ghosting, the error in the band behind
  scene.mover (quality/ghosting.h), beside the rest of the frame's.

Prints one table and writes a chart (SVG, standard library only): error
(1 - SSIM on the orbit) and flicker against cost, with each measure's
Pareto front (the configurations no other beats on both).

  bench/bench_taa.py [--width 320 --height 240] [--lights 64] [--frames 30]
      [--repeat 2] [--temporal 6] [--svg FILE] [--json FILE] [--from-json FILE]

MSAA's reference renders at the job's msaa too (the harness's rule); TAA's
leaves TAA out (a reference drops anti-aliasing effects), so each is scored
against a truth of at least 4 x 4 samples a pixel."""

import argparse
import json
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "e2e"))
import testlib  # noqa: E402
import benchrun  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--width", type=int, default=320)
ap.add_argument("--height", type=int, default=240)
ap.add_argument("--lights", type=int, default=64)
ap.add_argument("--intensity", type=float, default=0.5, help="scene.light_intensity")
ap.add_argument("--frames", type=int, default=30, help="timed frames of the cost jobs")
ap.add_argument("--repeat", type=int, default=2)
ap.add_argument("--temporal", type=int, default=6, help="frames in a row for flicker")
ap.add_argument("--techniques", default="forward,clustered_deferred")
ap.add_argument("--svg", default="bench-taa.svg", help="chart file ('' for none)")
ap.add_argument("--json", help="write every result here")
ap.add_argument("--from-json", help="report on the results a --json run wrote, without running")
args = ap.parse_args()

TECHS = args.techniques.split(",")
AA = [("none", {}, 1), ("msaa2", {}, 2), ("msaa4", {}, 4), ("taa", {"post": ["taa"]}, 1),
      ("taa_aabb", {"post": [{"taa": {"clamp": "aabb"}}]}, 1)]
CONFIGS = [(t, a) for t in TECHS for a, _, _ in AA]
HISTORY = 16  # TAA's default: the still and moving jobs draw it before their capture


def scene(**kw):
    s = {"preset": "lights", "lights": args.lights, "light_intensity": args.intensity,
         "width": args.width, "height": args.height}
    s.update(kw)
    return s


def job(tech, aa, kind):
    look, msaa = next((lk, m) for a, lk, m in AA if a == aa)
    j = {"technique": tech, "msaa": msaa}
    if look:
        j["look"] = look
    orbit = {"path": "orbit", "period": 240}
    if kind == "cost":
        j.update(frames=args.frames, warmup_frames=HISTORY, capture_interval=0,
                 scene=scene(camera=orbit))
    else:
        j.update(frames=HISTORY + 1, warmup_frames=0, capture_interval=HISTORY + 1,
                 metrics=["ssim", "flip", "psnr"],
                 reference={"technique": "forward", "supersample": 4})
        if kind == "still":
            j["scene"] = scene()
        else:
            j["scene"] = scene(camera=orbit, mover={"period": 60})
            j["temporal"] = {"frames": args.temporal}
    return j


results = {"%s/%s/%s" % (t, a, k): [] for t, a in CONFIGS for k in ("cost", "still", "moving")}
if args.from_json:
    with open(args.from_json) as f:
        results.update(json.load(f))
bench = benchrun.Run()
d = None if args.from_json else testlib.Daemon()
try:
    if d:
        info = d.json("GET", "/v1/info")[1]["device"]
        print("device: %s | %s | %s" % (info["gl_renderer"], info["gl_version"], info["egl_device"]))
        print("scene: lights preset, %d lights (intensity %g), %dx%d; cost: %d timed frames after %d "
              "warm-up on an orbit, %d interleaved rounds; accuracy: frame %d against forward "
              "supersampled 4x4; stability: %d frames in a row on the orbit with scene.mover"
              % (args.lights, args.intensity, args.width, args.height, args.frames, HISTORY,
                 args.repeat, HISTORY + 1, args.temporal))
        bench.start()
        print()
        for kind in ("still", "moving"):
            for t, a in CONFIGS:
                t0 = time.time()
                done = d.wait(d.submit(job(t, a, kind)), timeout=7200)
                if done.get("status") != "done":
                    sys.exit("%s %s (%s) failed: %s" % (t, a, kind, done.get("error")))
                results["%s/%s/%s" % (t, a, kind)].append(done["result"])
                print("  %-20s %-9s %-6s (%.0f s)" % (t, a, kind, time.time() - t0), flush=True)
        for rep in range(args.repeat):
            for t, a in CONFIGS:
                done = d.wait(d.submit(job(t, a, "cost")), timeout=7200)
                if done.get("status") != "done":
                    sys.exit("%s %s (cost) failed: %s" % (t, a, done.get("error")))
                r = done["result"]
                results["%s/%s/cost" % (t, a)].append(r)
                print("  [%d/%d] %-20s %-9s frame %8.2f ms" % (rep + 1, args.repeat, t, a,
                                                             r["frame_ms"]["median"]), flush=True)
finally:
    if d:
        d.stop()
        d.cleanup()
if d:
    bench.end([r for rs in results.values() for r in rs])
if args.json and not args.from_json:
    with open(args.json, "w") as f:
        json.dump(results, f)


def cost(t, a, series="frame_ms"):
    rs = results["%s/%s/cost" % (t, a)]
    if series == "work":
        return statistics.median(benchrun.cpu_work_ms(r) for r in rs)
    return statistics.median(r["frame_ms"]["median"] for r in rs)


def passes(t, a, names):
    """Median over the cost runs of the summed median time of the passes named."""
    rs = results["%s/%s/cost" % (t, a)]
    return statistics.median(sum(v["median"] for k, v in r["gpu_sections_ms"].items() if k in names)
                             for r in rs)


def quality(t, a, kind, key):
    r = results["%s/%s/%s" % (t, a, kind)][0]
    q = r["quality"]
    if key == "ssim":
        return q["worst_ssim"]["value"]
    if key == "flip":
        return q["worst_flip"]["mean"]
    if key == "psnr":
        return q["worst_psnr"]["value"]
    tmp = r["captures"][-1].get("temporal", {})
    if key == "flicker":
        return tmp.get("flicker")
    g = tmp.get("ghosting") or {}
    return g.get(key)


rows = []
for t, a in CONFIGS:
    rows.append({"technique": t, "aa": a, "frame_ms": cost(t, a), "ratio": cost(t, a) / cost(t, "none"),
                 "work_ms": cost(t, a, "work"), "work_ratio": cost(t, a, "work") / cost(t, "none", "work"),
                 "aa_ms": passes(t, a, ("msaa_resolve", "motion_vectors", "taa.resolve")),
                 "still_ssim": quality(t, a, "still", "ssim"), "still_flip": quality(t, a, "still", "flip"),
                 "still_psnr": quality(t, a, "still", "psnr"),
                 "moving_ssim": quality(t, a, "moving", "ssim"),
                 "moving_flip": quality(t, a, "moving", "flip"),
                 "flicker": quality(t, a, "moving", "flicker"),
                 "band": quality(t, a, "moving", "band_error"),
                 "rest": quality(t, a, "moving", "rest_error")})

print("\n| technique | AA | frame_ms | x none | cpu_work_ms | x none | AA passes ms | SSIM still | "
      "FLIP still | PSNR still | SSIM orbit | FLIP orbit | flicker | band error | rest error |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for r in rows:
    print("| %s | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.5f | %.4f | %.2f | %.5f | %.4f | %.5f | %.4f | %.4f |"
          % (r["technique"], r["aa"], r["frame_ms"], r["ratio"], r["work_ms"], r["work_ratio"],
             r["aa_ms"], r["still_ssim"], r["still_flip"], r["still_psnr"], r["moving_ssim"],
             r["moving_flip"], r["flicker"], r["band"], r["rest"]))


def pareto(points):
    """The points (x, y, label) no other beats on both x and y (lower is better)."""
    return sorted([p for p in points if not any(q[0] <= p[0] and q[1] <= p[1] and q[:2] != p[:2]
                                                for q in points)])


for key, what in (("moving_ssim", "1 - SSIM on the orbit"), ("flicker", "flicker")):
    pts = [(r["ratio"], (1 - r[key]) if key.endswith("ssim") else r[key],
            "%s %s" % (r["technique"], r["aa"])) for r in rows]
    print("\nPareto front, cost (x none) against %s: %s"
          % (what, ", ".join("%s (%.2f, %.5f)" % (p[2], p[0], p[1]) for p in pareto(pts))))

if args.svg:
    W, H, L, R, T, B, GAP = 900, 420, 60, 20, 40, 50, 70
    pw = (W - L - R - GAP) / 2
    colours = {"none": "#000000", "msaa2": "#1f77b4", "msaa4": "#17becf", "taa": "#d62728",
               "taa_aabb": "#ff7f0e"}
    marks = {TECHS[0]: "circle", TECHS[-1]: "square"}
    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="sans-serif" '
           'font-size="12"><rect width="100%%" height="100%%" fill="white"/>' % (W, H)]
    xmax = max(r["ratio"] for r in rows) * 1.05
    for panel, (key, what) in enumerate((("moving_ssim", "1 - SSIM (orbit)"), ("flicker", "flicker"))):
        x0 = L + panel * (pw + GAP)
        ys = [(1 - r[key]) if key.endswith("ssim") else r[key] for r in rows]
        ymax = max(ys) * 1.1

        def px(v):
            return x0 + (v - 0.8) / (xmax - 0.8) * pw

        def py(v):
            return H - B - v / ymax * (H - T - B)
        out.append('<rect x="%.1f" y="%d" width="%.1f" height="%d" fill="none" stroke="#999"/>'
                   % (x0, T, pw, H - T - B))
        for k in range(5):
            v = ymax * k / 4
            out.append('<text x="%.1f" y="%.1f" text-anchor="end">%.3g</text>' % (x0 - 4, py(v) + 4, v))
        for k in range(5):
            v = 0.8 + (xmax - 0.8) * k / 4
            out.append('<text x="%.1f" y="%d" text-anchor="middle">%.2f</text>' % (px(v), H - B + 16, v))
        out.append('<text x="%.1f" y="%d" text-anchor="middle">frame_ms / no anti-aliasing</text>'
                   % (x0 + pw / 2, H - B + 34))
        out.append('<text x="%.1f" y="%d">%s against cost</text>' % (x0, T - 8, what))
        pts = [(r["ratio"], y, r) for r, y in zip(rows, ys)]
        front = pareto([(p[0], p[1], i) for i, p in enumerate(pts)])
        out.append('<polyline fill="none" stroke="#888" stroke-dasharray="4,3" points="%s"/>'
                   % " ".join("%.1f,%.1f" % (px(p[0]), py(p[1])) for p in front))
        for x, y, r in pts:
            c = colours.get(r["aa"], "#555")
            if marks.get(r["technique"]) == "square":
                out.append('<rect x="%.1f" y="%.1f" width="8" height="8" fill="%s"/>' % (px(x) - 4, py(y) - 4, c))
            else:
                out.append('<circle cx="%.1f" cy="%.1f" r="4.5" fill="%s"/>' % (px(x), py(y), c))
    lx = L + 10
    for k, (a, c) in enumerate(colours.items()):
        out.append('<rect x="%d" y="%d" width="10" height="10" fill="%s"/><text x="%d" y="%d">%s</text>'
                   % (lx + 90 * k, H - 14, c, lx + 90 * k + 14, H - 5, a))
    out.append('<text x="%d" y="%d">circle: %s, square: %s; dashed: Pareto front; %dx%d, llvmpipe</text>'
               % (lx + 460, H - 5, TECHS[0], TECHS[-1], args.width, args.height))
    out.append("</svg>")
    with open(args.svg, "w") as f:
        f.write("\n".join(out))
    print("\nchart: %s" % args.svg)
