#!/usr/bin/env python3
"""The Khronos reference (issue 32; docs/assets.md, "Fidelity against the
Khronos viewer"): POST /v1/assets/NAME/fidelity on generated assets
(tests/e2e/gltf_gen.py) renders them with the glTF Sample Viewer in headless
Chromium and compares shadebench's lit image and look.debug channels with
the viewer's. Checks each channel's SSIM against the figure measured for it
(docs/assets.md), the lit image within its measured tolerance, the images
downloadable, the reference cached (a second request renders nothing), a
look the viewer cannot draw refused naming its field, and a daemon without
Chromium or without the viewer answering 503 naming what is missing (and
saying so in /v1/info), and a job cancelled while the viewer renders.
Small images (96x72): 57 s under make check on the 2-core machine
(docs/testing.md)."""
import os
import shutil
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_gen  # noqa: E402
from testlib import Daemon, check, finish, png_info, stop_and_check  # noqa: E402

W, H = 96, 72
# What each channel reaches at 96x72 on the generated box whose occlusion
# map names TEXCOORD_1 (texcoord_asset), measured (docs/assets.md): the
# lowest of luma and RGB SSIM. The bound sits just under it.
CHANNEL_MIN_SSIM = {
    "base_color": 0.99, "metallic": 0.99, "roughness": 0.99, "occlusion": 0.99,
    "emissive": 0.99, "alpha": 0.99, "geometric_normal": 0.99, "shading_normal": 0.99,
    "uv0": 0.99, "uv1": 0.99,
}
LIT_MIN_SSIM = 0.99  # the punctual look's tolerance (docs/assets.md)

chromium = shutil.which("chromium") or shutil.which("chromium-browser")
check(chromium is not None, "chromium is installed (tools/setup installs it)")
check(os.path.exists("reference-viewer/gltf-viewer.module.js"),
      "the Khronos viewer is vendored in build/reference-viewer (tools/setup)")

d = Daemon()
try:
    st, info = d.json("GET", "/v1/info")
    ref = info.get("reference", {})
    check(ref.get("available") is True, "/v1/info: the reference is available (%s)" % ref)
    st, _, body = d.request("PUT", "/v1/assets/box.glb", gltf_gen.texcoord_asset(1, False).glb())
    check(st == 201, "the asset uploads (%d)" % st)

    # Refusals, before anything renders.
    st, e = d.json("POST", "/v1/assets/box.glb/fidelity", {"look": {"lighting": "phong"}})
    check(st == 400 and e.get("error", {}).get("field") == "look.lighting",
          "a Phong look is refused naming look.lighting (%d %s)" % (st, e))
    st, e = d.json("POST", "/v1/assets/box.glb/fidelity", {"channels": ["albedo"]})
    check(st == 400 and e.get("error", {}).get("field") == "fidelity.channels[0]",
          "an unknown channel is refused naming it (%d %s)" % (st, e))
    st, e = d.json("POST", "/v1/assets/nothere.glb/fidelity", {})
    check(st == 400 and e.get("error", {}).get("field") == "scene.asset",
          "an unknown asset is refused naming scene.asset (%d %s)" % (st, e))
    st, e = d.json("GET", "/v1/assets/box.glb/fidelity")
    check(st == 405, "GET on the fidelity route is 405 (%d)" % st)

    # The comparison.
    req = {"width": W, "height": H}
    st, sub = d.json("POST", "/v1/assets/box.glb/fidelity", req)
    check(st == 202, "POST /v1/assets/box.glb/fidelity is accepted (%d %s)" % (st, sub))
    job = d.wait(sub["id"])
    check(job.get("status") == "done", "the fidelity job is done (%s: %s)" % (
        job.get("status"), job.get("error")))
    f = job.get("result", {}).get("fidelity", {})
    chans = f.get("channels", {})
    check(f.get("cache_hit") is False, "the first request renders the reference")
    cost = f.get("cost", {})
    check(all(cost.get(k, 0) > 0 for k in ("chromium_start_ms", "page_ms", "load_ms")),
          "the reference's cost is reported (%s)" % cost)
    lit = chans.get("lit", {})
    check(lit.get("ssim", 0) >= LIT_MIN_SSIM and lit.get("ssim_rgb", 0) >= LIT_MIN_SSIM,
          "lit: SSIM %.5f / %.5f >= %.2f" % (lit.get("ssim", 0), lit.get("ssim_rgb", 0), LIT_MIN_SSIM))
    for name, bound in CHANNEL_MIN_SSIM.items():
        m = chans.get(name, {})
        s = min(m.get("ssim", 0), m.get("ssim_rgb", 0))
        check(s >= bound, "%s: SSIM %.5f >= %.2f (%s)" % (name, s, bound, m.get("error", "")))
    # Both renders and the difference images are served.
    for kind in ("shadebench", "khronos", "ssim_map", "flip_map"):
        rel = lit.get("files", {}).get(kind)
        path = os.path.join(d.tmp, kind + ".png")
        ok = rel and d.download("/v1/jobs/%s/%s" % (sub["id"], rel), path) == 200
        pi = (png_info(path) or {}) if ok else {}
        # The SSIM map is the valid region: the window's border off.
        check(ok and (kind == "ssim_map" or (pi.get("width"), pi.get("height")) == (W, H)),
              "lit %s image downloads (%s %s)" % (kind, rel, pi))
    st, _, _ = d.request("GET", "/v1/jobs/%s/fidelity/..%%2fjob.json" % sub["id"])
    check(st in (400, 404), "a path outside fidelity/ is refused (%d)" % st)

    # The cache: the same request again renders nothing and compares the same.
    st, sub2 = d.json("POST", "/v1/assets/box.glb/fidelity", req)
    job2 = d.wait(sub2["id"])
    f2 = job2.get("result", {}).get("fidelity", {})
    check(f2.get("cache_hit") is True, "the second request is a cache hit")
    check(f2.get("cache_key") == f.get("cache_key"), "with the same key")
    check(abs(f2.get("channels", {}).get("lit", {}).get("ssim", 0) - lit.get("ssim", 1)) < 1e-9,
          "and the same lit SSIM")
    # Another camera is another key.
    st, sub3 = d.json("POST", "/v1/assets/box.glb/fidelity",
                      {"width": W, "height": H, "channels": ["base_color"],
                       "camera": {"eye": [2, 1.5, 3], "target": [0, 0, 0], "yfov_deg": 50}})
    job3 = d.wait(sub3["id"])
    f3 = job3.get("result", {}).get("fidelity", {})
    check(job3.get("status") == "done" and f3.get("cache_hit") is False and
          f3.get("cache_key") != f.get("cache_key"),
          "an explicit camera renders anew (%s %s)" % (job3.get("status"), job3.get("error")))
    bc = f3.get("channels", {}).get("base_color", {})
    check(min(bc.get("ssim", 0), bc.get("ssim_rgb", 0)) >= CHANNEL_MIN_SSIM["base_color"],
          "base_color from the explicit camera: SSIM %s" % bc.get("ssim"))

    # Cancelled while the viewer renders: Chromium is killed with its group
    # and the job ends cancelled.
    st, sub4 = d.json("POST", "/v1/assets/box.glb/fidelity",
                      {"width": W, "height": H, "channels": ["base_color"],
                       "camera": {"eye": [-2, 1.5, 3], "target": [0, 0, 0], "yfov_deg": 50}})
    deadline = time.time() + 120
    phase = None
    while time.time() < deadline:
        st, j = d.json("GET", "/v1/jobs/%s" % sub4["id"])
        phase = j.get("phase")
        if phase == "fidelity" or j.get("status") not in ("queued", "running"):
            break
        time.sleep(0.2)
    time.sleep(1.0)  # Chromium is starting
    t0 = time.time()
    st, _ = d.json("DELETE", "/v1/jobs/%s" % sub4["id"])
    job4 = d.wait(sub4["id"])
    check(phase == "fidelity" and job4.get("status") == "cancelled",
          "a fidelity job cancelled in its fidelity phase ends cancelled (%s, %s: %s)" % (
              phase, job4.get("status"), job4.get("error")))
    check(time.time() - t0 < 30, "within 30 s of the DELETE (%.1f s)" % (time.time() - t0))
    stop_and_check(d)  # a clean exit: under the sanitizers, no error and no leak
finally:
    d.stop()
    d.cleanup()

# Without Chromium, and without the viewer: the daemon runs and says so.
for args, what in ((["--chromium", "/nonexistent/chromium"], "Chromium"),
                   (["--reference-viewer", "/nonexistent/viewer"], "Sample Viewer")):
    d = Daemon(*args)
    try:
        st, info = d.json("GET", "/v1/info")
        ref = info.get("reference", {})
        check(ref.get("available") is False and what in ref.get("missing", ""),
              "%s missing: /v1/info says so (%s)" % (what, ref))
        d.request("PUT", "/v1/assets/box.glb", gltf_gen.texcoord_asset(1, False).glb())
        st, e = d.json("POST", "/v1/assets/box.glb/fidelity", {"width": W, "height": H})
        err = e.get("error", {})
        check(st == 503 and err.get("field") == "fidelity" and what in err.get("message", ""),
              "%s missing: 503 naming it (%d %s)" % (what, st, e))
        st, _ = d.json("GET", "/healthz")
        check(st == 200, "%s missing: the daemon still serves (%d)" % (what, st))
        stop_and_check(d)
    finally:
        d.stop()
        d.cleanup()

finish("e2e_fidelity")
