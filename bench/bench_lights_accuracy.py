#!/usr/bin/env python3
"""The many-lights family's error against forward: every technique at its
defaults, and every option that changes the image (light bounds, g-buffer
layouts, CPU binning), scored against forward on the same frame (SSIM,
PerceptualDiff, FLIP, PSNR), on the thesis grid and the lights preset.

  bench/bench_lights_accuracy.py [--width W --height H] [--scenes grid:10,lights:256]
                                 [--frames N] [--json FILE]

Prints a Markdown table (the README's accuracy table comes from it)."""

import json
import sys

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--width", type=int, default=540)
ap.add_argument("--height", type=int, default=360)
ap.add_argument("--scenes", default="grid:10,lights:256", help="preset:lights,...")
ap.add_argument("--frames", type=int, default=4, help="timed frames; the last is scored")
ap.add_argument("--json", help="write every result here")
args = ap.parse_args()

CONFIGS = [
    ("deferred", {}),
    ("deferred", {"light_bounds": "scissor_loose"}),
    ("deferred", {"light_bounds": "volume"}),
    ("deferred", {"light_bounds": "fullscreen"}),
    ("deferred", {"gbuffer": {"normal": "float3"}}),
    ("deferred", {"gbuffer": {"normal": "xy_reconstruct_z"}}),
    ("deferred", {"gbuffer": {"albedo": "pack_shift"}}),
    ("deferred", {"gbuffer": {"albedo": "pack_base10"}}),
    ("tiled_deferred", {}),
    ("tiled_deferred", {"binning": "cpu"}),
    ("forward_plus", {}),
    ("clustered_forward", {}),
    ("clustered_deferred", {}),
]

rows, everything = [], []
d = testlib.Daemon()
try:
    for scene in args.scenes.split(","):
        preset, lights = scene.split(":")
        for tech, opts in CONFIGS:
            job = {"technique": tech, tech: opts, "frames": args.frames, "warmup_frames": 1,
                   "capture_interval": args.frames, "reference": "forward",
                   "scene": {"preset": preset, "lights": int(lights), "dynamic": True,
                             "width": args.width, "height": args.height}}
            done = d.wait(d.submit(job), timeout=3600)
            if done.get("status") != "done":
                sys.exit("%s %s failed: %s" % (tech, opts, done.get("error")))
            m = done["result"]["captures"][-1]["metrics"]
            everything.append(done)
            row = (preset, lights, tech, json.dumps(opts) if opts else "defaults", m["ssim"],
                   m["pdiff"]["pass"], m["pdiff"]["failing_pixels"], m["flip"]["mean"],
                   m["psnr"]["overall"])
            rows.append(row)
            print("  %s %s %s %s: SSIM %.6f" % row[:5], flush=True)
finally:
    d.stop()
    d.cleanup()

print("\n%dx%d, frame %d of a moving-light run, against forward:\n" % (args.width, args.height,
                                                                      args.frames))
print("| scene | technique | options | SSIM | PerceptualDiff (failing pixels) | FLIP mean | PSNR dB |")
print("|---|---|---|---|---|---|---|")
for preset, lights, tech, opts, ssim, ok, fail, flip, psnr in rows:
    print("| %s, %s lights | %s | %s | %.6f | %s (%d) | %.5f | %s |"
          % (preset, lights, tech, opts.replace('"', ""), ssim, "pass" if ok else "FAIL", fail, flip,
             "identical" if psnr is None else "%.1f" % psnr))
benchrun.write_json(args.json, everything)
