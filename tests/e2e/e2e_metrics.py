"""Image-quality metrics in jobs and in shadebench-compare: forward against
itself is perfect, unlit against forward shows the difference, OSL against
forward passes, difference images download, bad metric options name their
field, a reference that cannot run fails the job, and the CLI's exit codes."""

import json
import os
import struct
import subprocess
import zlib

import testlib
from testlib import check

testlib.skip_without_egl()
COMPARE = os.environ.get("SHADEBENCH_COMPARE", "./shadebench-compare")
SCENE = {"width": 256, "height": 192}
JOB = {"frames": 6, "warmup_frames": 1, "capture_interval": 3, "scene": SCENE,
       "reference": "forward"}


def write_png(path, width, height, depth, colour_type, channels):
    """A minimal PNG writer (standard library only) for odd formats."""
    bytes_per = depth // 8 * channels
    raw = b"".join(b"\0" + bytes(width * bytes_per) for _ in range(height))
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, depth, colour_type, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw)))
        f.write(chunk(b"IEND", b""))


d = testlib.Daemon()
try:
    # forward against forward: perfect scores on every capture.
    job = d.run(dict(JOB, technique="forward"))
    check(job["status"] == "done", "forward vs forward done: %s" % job.get("error"))
    caps = job["result"]["captures"]
    check(len(caps) == 2, "two captures")
    for c in caps:
        m = c.get("metrics", {})
        check(m.get("ssim") == 1.0 and m.get("ssim_rgb") == 1.0, "SSIM 1 at frame %d: %s" % (c["frame"], m.get("ssim")))
        check(m.get("pdiff", {}).get("pass") is True and m["pdiff"]["failing_pixels"] == 0, "pdiff passes with 0 pixels")
        check(m.get("flip", {}).get("mean") == 0.0, "FLIP 0")
        check(m.get("psnr", {}).get("overall") is None and m["psnr"]["identical"] is True,
              "PSNR is null with identical: true")
    q = job["result"].get("quality", {})
    check(q.get("reference") == "forward" and q.get("captures_compared") == 2, "quality summary")
    check(q.get("worst_ssim", {}).get("value") == 1.0 and q.get("pdiff_failed_captures") == 0,
          "summary: worst SSIM 1, no PerceptualDiff failures")

    # Difference images and the reference frame download as PNGs of the right size.
    c = caps[0]
    for key, size in (("reference_url", (256, 192)), ("ssim_map_url", (246, 182)), ("flip_map_url", (256, 192))):
        path = os.path.join(d.tmp, key + ".png")
        check(d.download(c[key], path) == 200, "%s downloads" % key)
        info = testlib.png_info(path)
        check(info and (info["width"], info["height"]) == size, "%s is %s: %s" % (key, size, info))

    # unlit against forward: the metrics show the difference.
    job = d.run(dict(JOB, technique="unlit"))
    check(job["status"] == "done", "unlit vs forward done: %s" % job.get("error"))
    m = job["result"]["captures"][0]["metrics"]
    check(m["ssim"] < 0.95, "unlit SSIM well below 1: %s" % m["ssim"])
    check(m["pdiff"]["pass"] is False and m["pdiff"]["failing_pixels"] > 100, "unlit fails PerceptualDiff")
    check(m["flip"]["mean"] > 0.05 and m["psnr"]["overall"] < 40, "unlit FLIP and PSNR show it: %s" % m["flip"])
    q = job["result"]["quality"]
    check(q["pdiff_failed_captures"] == 2 and q["pdiff_failed_frames"] == [3, 6], "both captures fail")
    check(q["worst_flip"]["mean"] >= m["flip"]["mean"], "worst FLIP is the worst")

    # OSL against forward (still lights): passes, SSIM near 1 (the thesis:
    # 0.9999). 64 texels an object show it as well as the thesis's 256
    # (0.99997 against 0.99999), in a seventh of the time; e2e_osl.py holds
    # 256 texels to their stated bound.
    job = d.run(dict(JOB, technique="osl", osl={"resolution": 64},
                     scene=dict(SCENE, width=320, height=240)))
    check(job["status"] == "done", "osl vs forward done: %s" % job.get("error"))
    q = job["result"]["quality"]
    check(q["worst_ssim"]["value"] > 0.999 and q["pdiff_failed_captures"] == 0,
          "OSL matches forward: SSIM %s, PerceptualDiff failures %s" % (q["worst_ssim"], q["pdiff_failed_captures"]))

    # Only the metrics asked for, with their parameters.
    job = d.run(dict(JOB, technique="unlit", metrics={"pdiff": {"fov": 45, "threshold_pixels": 10 ** 9},
                                                       "flip": False, "psnr": False}))
    m = job["result"]["captures"][0]["metrics"]
    check("flip" not in m and "psnr" not in m and "ssim" in m, "flip and psnr switched off: %s" % sorted(m))
    check(m["pdiff"]["fov"] == 45 and m["pdiff"]["pass"] is True, "pdiff options applied")
    check("flip_map_url" not in job["result"]["captures"][0], "no FLIP map without FLIP")
    job = d.run(dict(JOB, technique="unlit", metrics=["psnr"]))
    picked = sorted(k for k in job["result"]["captures"][0]["metrics"] if k != "timing_ms")
    check(picked == ["psnr"], "a list picks metrics: %s" % picked)

    # Bad metric options name the field.
    for body, field in (({"reference": "forward", "capture_interval": 0}, "reference"),
                        (dict(JOB, reference="no_such_technique"), "reference"),
                        (dict(JOB, reference=None, metrics=["ssim"]), "metrics"),
                        (dict(JOB, metrics={"pdiff": {"fov": -1}}), "metrics.pdiff.fov"),
                        (dict(JOB, metrics={"pdiff": {"fvo": 20}}), "metrics.pdiff.fvo"),
                        (dict(JOB, metrics={"flip": {"pixels_per_degree": 0}}), "metrics.flip.pixels_per_degree"),
                        (dict(JOB, metrics={"ssim": {"window": 7}}), "metrics.ssim"),
                        (dict(JOB, metrics={"lpips": True}), "metrics.lpips"),
                        (dict(JOB, metrics=["ssim", "vmaf"]), "metrics"),
                        (dict(JOB, metrics=5), "metrics")):
        testlib.rejects(d, body, field)

    # A reference that cannot run fails the job with a clear error.
    job = d.run(dict(JOB, technique="forward", reference="osl", osl={"resolution": 1024}))
    check(job["status"] == "failed" and "reference osl cannot run" in job.get("error", ""),
          "unrunnable reference fails the job: %s" % job.get("error"))
    check(d.run(dict(JOB, technique="unlit"))["status"] == "done", "daemon serves on")
finally:
    d.stop()
check(d.proc.returncode == 0, "daemon exits 0 (got %s)" % d.proc.returncode)

# shadebench-compare: same JSON, exit 0 pass, 1 fail, 2 bad input.
tmp = d.tmp
a = os.path.join(tmp, "a.png")
b = os.path.join(tmp, "b.png")
subprocess.run([testlib.SHADEBENCHD, "--once", "/dev/stdin", "--out", os.path.join(tmp, "f")],
               input=json.dumps({"technique": "forward", "frames": 1, "warmup_frames": 0,
                                 "capture_interval": 1, "scene": SCENE}), text=True, capture_output=True)
subprocess.run([testlib.SHADEBENCHD, "--once", "/dev/stdin", "--out", os.path.join(tmp, "u")],
               input=json.dumps({"technique": "unlit", "frames": 1, "warmup_frames": 0,
                                 "capture_interval": 1, "scene": SCENE}), text=True, capture_output=True)
fwd, unl = os.path.join(tmp, "f", "frame-000001.png"), os.path.join(tmp, "u", "frame-000001.png")
out = subprocess.run([COMPARE, fwd, fwd], capture_output=True, text=True)
res = json.loads(out.stdout) if out.returncode == 0 else {}
check(out.returncode == 0 and res.get("ssim") == 1.0 and res["pdiff"]["pass"], "compare: identical passes, exit 0")
check({"ssim", "ssim_rgb", "ssim_min", "pdiff", "psnr", "flip"} <= set(res), "compare prints every metric")
diff_dir = os.path.join(tmp, "diff")
out = subprocess.run([COMPARE, fwd, unl, "--fov", "22.6", "--diff-out", diff_dir], capture_output=True, text=True)
check(out.returncode == 1 and json.loads(out.stdout)["pdiff"]["pass"] is False, "compare: visible difference exits 1")
check(os.path.exists(os.path.join(diff_dir, "ssim.png")) and os.path.exists(os.path.join(diff_dir, "flip.png")),
      "--diff-out writes ssim.png and flip.png")
out = subprocess.run([COMPARE, fwd, unl, "--metrics", "ssim,psnr"], capture_output=True, text=True)
check(out.returncode == 0 and "pdiff" not in json.loads(out.stdout), "without pdiff there is nothing to fail")
small = os.path.join(tmp, "small.png")
write_png(small, 128, 96, 8, 2, 3)
sixteen = os.path.join(tmp, "sixteen.png")
write_png(sixteen, 256, 192, 16, 2, 3)
grey = os.path.join(tmp, "grey.png")
write_png(grey, 256, 192, 8, 0, 1)
for args, why in (([fwd, os.path.join(tmp, "missing.png")], "unreadable file"),
                  ([fwd, small], "size mismatch"),
                  ([fwd, sixteen], "16-bit PNG"),
                  ([fwd, grey], "greyscale PNG"),
                  ([fwd, fwd, "--metrics", "lpips"], "unknown metric"),
                  ([fwd, fwd, "--fov", "abc"], "bad --fov")):
    out = subprocess.run([COMPARE] + args, capture_output=True, text=True)
    check(out.returncode == 2 and out.stderr.strip(), "compare: %s exits 2 with a message (%d %s)"
          % (why, out.returncode, out.stderr.strip()))
if testlib.failures:
    d.dump_log()
d.cleanup(keep=testlib.failures > 0)
testlib.finish("e2e_metrics")
