"""The visibility buffer (issue 37) against forward, on small frames:
- every preset and an uploaded textured asset (gltf_gen's showcase court:
  normal, metallic-roughness and emissive maps, a masked fence, a glass
  pane, point, spot and directional lights), at MSAA 1 and 4: SSIM >=
  0.9999 and PerceptualDiff passes;
- by default through the clustered lights (the froxel grid); every light
  (forward's loop) and 64-bit ids draw the same image;
- its passes are timed, and it keeps fewer bytes a pixel than the
  g-buffer of clustered_deferred under the same look (result figures)."""

import os
import tempfile

import gltf_gen
import testlib
from testlib import check

testlib.skip_without_egl()

W, H = 96, 72
JOB = {"frames": 1, "warmup_frames": 0, "capture_interval": 1}
SSIM_BOUND = 0.9999
PRESETS = ("grid", "lights", "teapots", "chart", "sphere", "plane", "textured")


def run(d, job, what):
    done = d.run(job)
    check(done.get("status") == "done", "%s runs: %s" % (what, done.get("error")))
    return done.get("result", {})


def agrees(result, what):
    q = result.get("quality", {})
    ssim = q.get("worst_ssim", {}).get("value", 0)
    return check(ssim >= SSIM_BOUND and q.get("pdiff_failed_captures") == 0,
                 "%s agrees with forward: SSIM %.6f (>= %s), PerceptualDiff failures %s"
                 % (what, ssim, SSIM_BOUND, q.get("pdiff_failed_captures")))


d = testlib.Daemon()
lights_result = {}
try:
    out = tempfile.mkdtemp(prefix="shadebench-vis-")
    path = os.path.join(out, "court.glb")
    with open(path, "wb") as f:
        f.write(gltf_gen.showcase_asset().glb())
    with open(path, "rb") as f:
        status, body = d.json("PUT", "/v1/assets/court.glb", f.read())
    check(status == 201, "upload court.glb: %d %s" % (status, body.get("error")))

    for msaa in (1, 4):
        for preset in PRESETS + ("court.glb",):
            scene = {"width": W, "height": H}
            if preset.endswith(".glb"):
                scene.update(asset=preset, lights=32, light_intensity=0.3)
            else:
                scene["preset"] = preset
            result = run(d, dict(JOB, technique="visibility_buffer", msaa=msaa,
                                 reference="forward", scene=scene),
                         "%s at msaa %d" % (preset, msaa))
            agrees(result, "%s at msaa %d" % (preset, msaa))
            vb = result.get("visibility_buffer", {})
            if preset == "court.glb":
                check(vb.get("material_passes", 0) > 1,
                      "an asset scene shades material by material: %s" % vb.get("material_passes"))
            if preset == "lights" and msaa == 1:
                lights_result = result
                passes = list(result.get("gpu_sections_ms", {}))
                check(passes[:4] == ["binning", "visibility", "classify", "shading"],
                      "every declared pass is timed: %s" % passes)
                check(vb.get("ids", "").startswith("r32ui") and vb.get("bytes_per_pixel") == 8.0,
                      "32-bit ids and depth: 8 bytes a pixel: %s" % vb)
                check(vb.get("lights") == "clustered" and "grid" in vb,
                      "the froxel grid's lights by default, described: %s" % sorted(vb))

    # Every light (forward's loop) and 64-bit ids draw what the froxel grid's lights do.
    for options, what, msaa in (({"lights": "all"}, "every light", 4),
                                ({"ids": "wide"}, "64-bit ids", 1)):
        result = run(d, dict(JOB, technique="visibility_buffer", msaa=msaa,
                             visibility_buffer=options, reference="forward",
                             scene={"preset": "lights", "lights": 128, "width": W, "height": H}),
                     "%s at msaa %d" % (what, msaa))
        agrees(result, "%s at msaa %d" % (what, msaa))
        vb = result.get("visibility_buffer", {})
        if options.get("lights"):
            check(vb.get("lights") == "all" and "grid" not in vb,
                  "every light, no grid: %s" % sorted(vb))
        else:
            check(vb.get("ids", "").startswith("rg32ui"), "wide ids: %s" % vb.get("ids"))

    # Fewer bytes a pixel than the g-buffer, same scene and look.
    vb = lights_result
    gb = run(d, dict(JOB, technique="clustered_deferred",
                     scene={"preset": "lights", "width": W, "height": H}), "clustered deferred")
    vbytes = vb.get("visibility_buffer", {}).get("bytes_per_pixel", 1e9)
    gbytes = gb.get("clustered_deferred", {}).get("gbuffer", {}).get("bytes_per_pixel", 0)
    check(0 < vbytes < gbytes, "visibility buffer %s bytes a pixel < g-buffer %s" % (vbytes, gbytes))
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_visibility")
