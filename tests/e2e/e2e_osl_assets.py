"""OSL on a generated textured asset (gltf_gen's showcase court, 8 moving
lights, 160x120): its defaults agree with forward (SSIM >= 0.999,
PerceptualDiff passes) and no pixel, along a chart's edge or anywhere, is
more than 32 levels from forward (each chart's rectangle filled from its
own surface at every level); shading density follows the screen (the
ground, near and far in one frame, is read at several levels) and the
texels shaded per covered pixel are reported; under an orbiting camera at
async distance 0 no block is read stale, and frame k is the same after 1
or 4 warm-up frames."""

import os

import gltf_gen
import testlib
from testlib import check

testlib.skip_without_egl()

SCENE = {"asset": "court.glb", "lights": 8, "light_intensity": 0.3, "dynamic": True,
         "width": 160, "height": 120}

d = testlib.Daemon()
try:
    status, up = d.json("PUT", "/v1/assets/court.glb", gltf_gen.showcase_asset().glb())
    check(status in (200, 201), "court uploaded: %s %s" % (status, up))
    job = {"technique": "osl", "frames": 2, "warmup_frames": 1, "capture_interval": 2,
           "reference": "forward", "scene": SCENE}
    done = d.run(job)
    check(done["status"] == "done", "osl on the court: %s" % done.get("error"))
    r = done["result"]
    q = r["quality"]
    check(q["worst_ssim"]["value"] >= 0.999 and q["pdiff_failed_captures"] == 0,
          "defaults against forward: SSIM %.5f >= 0.999, PerceptualDiff passes (%s failing pixels)"
          % (q["worst_ssim"]["value"], [c["metrics"]["pdiff"]["failing_pixels"] for c in r["captures"]]))
    cap = r["captures"][-1]
    mine, ref = os.path.join(d.tmp, "osl.png"), os.path.join(d.tmp, "forward.png")
    d.download(cap["url"], mine)
    d.download(cap["reference_url"], ref)
    diff = testlib.png_diff(ref, mine)
    check(diff and diff["max_abs"] <= 32,
          "no pixel more than 32 levels from forward (chart edges included): %s" % diff)
    o = r["osl"]
    vis = o["visibility"]
    levels = vis.get("blocks_read_by_level", [])
    check(o.get("levels", {}).get("count", 0) > 1 and sum(1 for n in levels if n > 0) >= 2,
          "density follows the screen: blocks read at several levels %s" % levels)
    tpp = vis.get("texels_per_covered_pixel", 0)
    check(vis.get("covered_pixels", 0) > 0 and 0 < tpp <= 4,
          "texels shaded per covered pixel reported, at most 4: %s" % tpp)
    check(o["asset_charts"]["gutter_texels"] >= 2, "gutters reported: %s" % o["asset_charts"])

    # A moving camera at async distance 0: every block read holds this
    # frame's shading; frame k does not depend on the frames before it.
    orbit = dict(job, reference=None, capture_interval=3, frames=3,
                 scene=dict(SCENE, camera={"path": "orbit", "period": 24}))
    paths = []
    for warm in (1, 4):
        done = d.run(dict(orbit, warmup_frames=warm))
        check(done["status"] == "done", "orbit: %s" % done.get("error"))
        o = done["result"]["osl"]
        check(o["visibility"]["stale_blocks"] == 0 and o["staleness"]["max"] == 0 and
              o["staleness"]["unshaded_reads"] == 0 and o["staleness"]["reads"] > 0,
              "orbit at async distance 0: no stale block (%s, %s)" % (o["visibility"], o["staleness"]))
        paths.append(os.path.join(d.tmp, "orbit-%d.png" % warm))
        d.download(done["result"]["captures"][-1]["url"], paths[-1])
    diff = testlib.png_diff(paths[0], paths[1])
    check(diff and diff["max_abs"] == 0, "orbit: frame 3 the same after 1 or 4 warm-up frames: %s" % diff)
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_osl_assets")
