#!/usr/bin/env python3
"""Uploaded glTF assets rendered (issue 21), end to end: gltf_gen.py's files
through PUT /v1/assets, the converter, the cache and every technique, at
96x72 and a couple of frames:
- every technique renders textured.glb (point, spot and directional lights
  of its own, 32 generated ones beside them) and agrees with forward: SSIM
  >= 0.999 and PerceptualDiff passing, osl (object-space shading of baked
  materials: docs/techniques.md) >= OSL_BOUND;
- the result names the asset and its SHA-256, and its load time;
- the normal map changes the image (textured.glb against no_normal_map.glb,
  otherwise the same file);
- osl shades an asset whose uv1 comes from the file and one whose uv1 the
  converter generated, and reports the charts' uncovered texels;
- alpha.glb (a masked and a blended material): every technique draws the
  blended pane in the harness's transparent pass and agrees with forward;
- a job pinned to another hash is refused naming scene.asset_sha256;
- a file that passes the converter's checks and crashes assimp 5.2 inside
  the converter (tests/fuzz/regressions/asset_convert) is answered 422, the
  loader's failure, and the daemon serves on."""

import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_gen  # noqa: E402
import testlib  # noqa: E402
from testlib import check  # noqa: E402

testlib.skip_without_egl()

SSIM_BOUND = 0.999
OSL_BOUND = 0.97
SCENE = {"width": 96, "height": 72, "lights": 32, "light_intensity": 0.3}
JOB = {"frames": 2, "warmup_frames": 1, "capture_interval": 2}


def quality(done):
    q = done.get("result", {}).get("quality", {})
    return q.get("worst_ssim", {}).get("value", 0), q.get("pdiff_failed_captures")


def main():
    out = tempfile.mkdtemp(prefix="shadebench-gltf-")
    gltf_gen.build_all(out)
    d = testlib.Daemon()
    try:
        for name in ("textured.glb", "no_normal_map.glb", "uv1_file.glb", "alpha.glb"):
            with open(os.path.join(out, name), "rb") as f:
                status, body = d.json("PUT", "/v1/assets/" + name, f.read())
            check(status == 201, "upload %s: %d %s" % (name, status, body.get("error")))
        techniques = [t["name"] for t in d.json("GET", "/v1/info")[1]["techniques"]]

        # Every technique on an uploaded asset against forward.
        scene = dict(SCENE, asset="textured.glb")
        for t in techniques:
            job = dict(JOB, technique=t, scene=scene)
            if t != "unlit":
                job["reference"] = "forward"
            done = d.run(job)
            check(done.get("status") == "done", "%s renders textured.glb: %s" % (t, done.get("error")))
            if t in ("unlit", "forward"):
                continue
            ssim, pdiff = quality(done)
            if t == "osl":
                check(ssim >= OSL_BOUND, "osl near forward on textured.glb: SSIM %.5f >= %s"
                      % (ssim, OSL_BOUND))
            else:
                check(ssim >= SSIM_BOUND and pdiff == 0,
                      "%s agrees with forward on textured.glb: SSIM %.5f, PerceptualDiff failures %s"
                      % (t, ssim, pdiff))
            if t == "clustered_deferred":
                asset = done["result"]["scene"].get("asset", {})
                spec_scene = done.get("spec", {}).get("scene", {})
                check(asset.get("name") == "textured.glb" and len(asset.get("sha256", "")) == 64
                      and asset.get("sha256") == spec_scene.get("asset_sha256"),
                      "the result and spec name the asset and its hash: %s" % asset.get("sha256"))
                load = asset.get("load_ms", {})
                check(load.get("read", -1) >= 0 and load.get("scene_and_upload", -1) > 0,
                      "the result reports the asset's load time: %s" % load)
                lights = asset.get("lights", {})
                check(lights.get("spot") == 1 and lights.get("directional") == 1,
                      "the asset's spot and directional lights are in the scene: %s" % lights)

        # The normal map changes the image.
        bumped = d.run(dict(JOB, technique="forward", scene=scene))
        flat = d.run(dict(JOB, technique="forward", scene=dict(SCENE, asset="no_normal_map.glb")))
        a = testlib.png_pixels(os.path.join(d.state, "jobs", bumped["id"], "frame-000002.png"))
        b = testlib.png_pixels(os.path.join(d.state, "jobs", flat["id"], "frame-000002.png"))
        differ = sum(1 for p, q in zip(a[2], b[2]) if p != q)
        check(differ > 50, "the normal map changes the image: %d of %d pixels differ"
              % (differ, len(a[2])))

        # OSL on the file's uv1 and on the converter's charts.
        for name, origin in (("uv1_file.glb", "file"), ("textured.glb", "generated")):
            done = d.run(dict(JOB, technique="osl", reference="forward",
                              scene=dict(SCENE, asset=name)))
            charts = done.get("result", {}).get("osl", {}).get("asset_charts", {})
            ssim, _ = quality(done)
            check(done.get("status") == "done" and ssim >= OSL_BOUND
                  and 0 <= charts.get("uncovered_share", -1) < 0.6,
                  "osl on uv1 from the %s: SSIM %.5f, charts %s" % (origin, ssim, charts))

        # Masked and blended materials.
        for t in techniques:
            job = dict(JOB, technique=t, scene=dict(SCENE, asset="alpha.glb"))
            if t not in ("unlit", "forward"):
                job["reference"] = "forward"
            done = d.run(job)
            sections = list(done.get("result", {}).get("gpu_sections_ms", {}))
            check(done.get("status") == "done" and "transparent" in sections,
                  "%s draws alpha.glb's glass in the transparent pass: %s %s"
                  % (t, sections, done.get("error")))
            if "reference" in job:
                ssim, pdiff = quality(done)
                bound = OSL_BOUND if t == "osl" else SSIM_BOUND
                check(ssim >= bound, "%s agrees with forward on alpha.glb: SSIM %.5f" % (t, ssim))

        # A pinned hash that is not the stored asset's.
        status, body = d.json("POST", "/v1/jobs", dict(JOB, technique="forward", scene=dict(
            SCENE, asset="textured.glb", asset_sha256="0" * 64)))
        check(status in (400, 409) and body.get("error", {}).get("field") == "scene.asset_sha256",
              "a job pinned to another hash is refused naming scene.asset_sha256: %d %s"
              % (status, body))

        # assimp crashing in the converter, a child process: a 422, no harm.
        crash = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "fuzz", "regressions",
                             "asset_convert", "assimp-segv-after-checks")
        with open(crash, "rb") as f:
            status, body = d.json("PUT", "/v1/assets/crash.glb", f.read())
        check(status == 422 and "loader failed" in body.get("error", {}).get("message", ""),
              "assimp's crash in the converter is a 422: %d %s" % (status, body))
        status, _ = d.json("GET", "/v1/assets/textured.glb")
        check(status == 200 and d.alive(), "the daemon serves on after the converter crashed")
    finally:
        testlib.stop_and_check(d)
    testlib.finish("e2e_asset_render")


main()
