#!/usr/bin/env python3
"""Issue 35's Done-when: OSL's defaults on a generated textured asset with
moving lights against forward, interleaved on one daemon. The asset is
tests/e2e/gltf_gen.py's showcase court (a textured ground spanning near and
far, normal-mapped boxes, an emissive box, a masked fence, a glass pane)
with --lights generated point lights circling (scene.dynamic). Prints per
round both frame_ms medians and cpu_work_ms (the daemon's CPU time per
timed frame) and the ratio; OSL's worst SSIM, PerceptualDiff failing
pixels and largest channel difference against forward (seams show there),
texels shaded per covered pixel, the blocks read at each level, stale
blocks; then the medians of the ratios. With --grid also the thesis grid
with still lights (1080x720), where the raster pass and the resolve are
OSL's whole frame.
  bench/bench_osl_assets.py [--rounds N] [--frames N] [--lights N] [--width W --height H]
                            [--osl JSON] [--grid | --grid-only]"""
import argparse
import json
import os
import statistics
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "e2e"))
import benchrun  # noqa: E402
import gltf_gen  # noqa: E402
import testlib  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--rounds", type=int, default=3)
ap.add_argument("--frames", type=int, default=8)
ap.add_argument("--warmup", type=int, default=2)
ap.add_argument("--lights", type=int, default=64)
ap.add_argument("--width", type=int, default=480)
ap.add_argument("--height", type=int, default=360)
ap.add_argument("--osl", default="{}", help="OSL options (JSON), the defaults when left out")
ap.add_argument("--grid", action="store_true", help="also the thesis grid with still lights")
ap.add_argument("--grid-only", action="store_true", help="the thesis grid with still lights alone")
args = ap.parse_args()

ASSET = {"asset": "court.glb", "lights": args.lights, "light_intensity": 0.15, "dynamic": True,
         "width": args.width, "height": args.height}
GRID = {"preset": "grid", "dynamic": False, "width": 1080, "height": 720}


def job(technique, scene, **kw):
    j = {"technique": technique, "frames": args.frames, "warmup_frames": args.warmup,
         "capture_interval": args.frames, "scene": scene}
    if technique == "osl":
        j["reference"] = "forward"
        j["osl"] = json.loads(args.osl)
    j.update(kw)
    return j


def max_abs(d, result):
    """Largest channel difference of the last capture against its reference."""
    cap = result["captures"][-1]
    a, b = os.path.join(d.tmp, "osl.png"), os.path.join(d.tmp, "ref.png")
    d.download(cap["url"], a)
    d.download(cap["reference_url"], b)
    diff = testlib.png_diff(b, a)
    return diff["max_abs"] if diff else None


bench = benchrun.Run()
d = testlib.Daemon()
results = []
try:
    dev = d.json("GET", "/v1/info")[1]["device"]
    print("device: %s | %s" % (dev["gl_renderer"], dev["gl_version"]))
    status, up = d.json("PUT", "/v1/assets/court.glb", gltf_gen.showcase_asset().glb())
    if status not in (200, 201):
        sys.exit("upload: %d %s" % (status, up))
    bench.start()
    sets = ([] if args.grid_only else [("court, moving lights", ASSET)]) + \
        ([("grid, still lights", GRID)] if args.grid or args.grid_only else [])
    for name, scene in sets:
        ratios, cpu_ratios = [], []
        for k in range(args.rounds):
            pair = [job("forward", scene), job("osl", scene)]
            got = {}
            for j in (pair if k % 2 == 0 else pair[::-1]):
                done = d.wait(d.submit(j), timeout=3600)
                if done.get("status") != "done":
                    sys.exit("%s: %s failed: %s" % (name, j["technique"], done.get("error")))
                got[j["technique"]] = done["result"]
                results.append(done["result"])
            f, o = got["forward"], got["osl"]
            ratio = o["frame_ms"]["median"] / f["frame_ms"]["median"]
            cpu = benchrun.cpu_work_ms(o) / benchrun.cpu_work_ms(f)
            ratios.append(ratio)
            cpu_ratios.append(cpu)
            q = o.get("quality", {})
            oo = o.get("osl", {})
            vis = oo.get("visibility", {})
            sections = {s: round(v["median"], 1) for s, v in o.get("gpu_sections_ms", {}).items()}
            print("%s, round %d: forward %.1f ms (cpu_work %.1f), osl %.1f ms (cpu_work %.1f): "
                  "x%.3f (cpu_work x%.3f); osl passes %s; worst SSIM %.5f, PerceptualDiff failing "
                  "%s, largest difference %s; %s texels per covered pixel (%s covered; %s per pixel), blocks read "
                  "by level %s, stale blocks %s, atlas %sx%s" %
                  (name, k + 1, f["frame_ms"]["median"], benchrun.cpu_work_ms(f),
                   o["frame_ms"]["median"], benchrun.cpu_work_ms(o), ratio, cpu, sections,
                   q.get("worst_ssim", {}).get("value", 0),
                   [c["metrics"]["pdiff"]["failing_pixels"] for c in o["captures"]],
                   max_abs(d, o), vis.get("texels_per_covered_pixel"), vis.get("covered_pixels"), vis.get("texels_per_pixel"),
                   vis.get("blocks_read_by_level"), vis.get("stale_blocks"),
                   oo.get("atlas", {}).get("width"), oo.get("atlas", {}).get("height")),
                  flush=True)
        print("%s: osl / forward, median of %d rounds: frame_ms x%.3f, cpu_work_ms x%.3f\n"
              % (name, args.rounds, statistics.median(ratios), statistics.median(cpu_ratios)),
              flush=True)
finally:
    testlib.stop_and_check(d)
bench.end(results)
