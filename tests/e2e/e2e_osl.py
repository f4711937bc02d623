"""Object Space Lighting end to end: it shows forward's image within the
stated texture-sampling bound, async shading shades fewer texels, the
lighting pass runs once for still lights, frame k is the same image however
the run started, visibility "seen" gives the same pixels from fewer texels
and counts what outruns it, hidden objects are not reshaded and objects
coming into view are shaded before they are read, osl.budget_texels holds
every frame and staleness stays within the schedule when it allows, the
defaults (auto tiles, seen) agree with forward, the thesis's configuration
is still whole tiles, and bad OSL options answer 400."""

import os

import testlib
from testlib import check

testlib.skip_without_egl()

# The thesis's 256 texels an object shade a 33-million-texel atlas on the
# first frame whatever the frame's size: 52 CPU seconds with the preset's 10
# lights on llvmpipe here, 25 with 2 (2026-11-27). Whole tiles shade each
# texel with shade_all_lights (lighting.glsl), forward's own light loop, so
# 256 runs with 2 lights; auto, whose light loop is its own (per-block
# culled), with 10. e2e_report holds whole tiles with 10 lights to forward
# (the thesis preset's still lights). A texel's shading stored one texel
# aside fails both: here mean 0.021, largest 127; there SSIM 0.9917.
LIGHTS = {"256": 2, "auto": 10}
# Static scene, measured on llvmpipe at 320x240: mean 0.007 and 0.033,
# largest 13 and 39, for 256 and auto with 10 lights; 256 with 2 lights: mean
# 0.0015, largest 12, so its bound went from 0.05 to 0.01 (about 7 times the
# mean, as before).
MEAN_BOUND = {"256": 0.01, "auto": 0.1}   # mean |difference| per channel, 0..255
MAX_BOUND = 48                            # largest difference, any channel

SCENE = {"width": 320, "height": 240}


def capture(d, job, name):
    done = d.run(job)
    check(done["status"] == "done", "%s done: %s" % (name, done.get("error")))
    path = os.path.join(d.tmp, name + ".png")
    d.download(done["result"]["captures"][-1]["url"], path)
    return done.get("result", {}), path


d = testlib.Daemon()
try:
    # A still scene: frame 2 is frame 4's image, and a reshade after the
    # first frame would show in either.
    static = {"frames": 2, "warmup_frames": 1, "capture_interval": 2, "scene": SCENE}
    for res in ("256", "auto"):
        scene = dict(SCENE, lights=LIGHTS[res])
        _, fwd = capture(d, dict(static, technique="forward", scene=scene), "forward-" + res)
        osl = {"resolution": int(res) if res.isdigit() else res, "visibility": "all"}
        result, path = capture(d, dict(static, technique="osl", osl=osl, scene=scene), "osl-" + res)
        diff = testlib.png_diff(fwd, path)
        check(diff and max(diff["mean_abs"]) <= MEAN_BOUND[res],
              "osl %s mean difference within %.2f: %s" % (res, MEAN_BOUND[res], diff))
        check(diff and diff["max_abs"] <= MAX_BOUND, "osl %s max difference <= %d" % (res, MAX_BOUND))
        o = result.get("osl", {})
        check(o.get("objects_reshaded_per_frame", {}).get("max") == 0,
              "still lights: no reshading after the first frame (%s)" % o.get("objects_reshaded_per_frame"))
        check(o.get("initial_shading", {}).get("objects") == 512, "first frame shades all 512")
        check(o.get("atlas", {}).get("bytes", 0) > 0, "atlas size reported")
        check({"lighting", "raster"} <= set(result.get("gpu_sections_ms", {})),
              "lighting and raster GPU times reported apart")
        if res == "256":
            # The thesis's own OSL, as the thesis preset pins it: whole tiles.
            check(o["atlas"]["width"] == 8192 and o["atlas"]["height"] == 4096 and
                  "visibility" not in o, "thesis mode: 512 whole tiles of 256x256 = 8192x4096")
            texels_256 = o["atlas"]["tile_texels"]
        else:
            check(o["atlas"]["tile_texels"] < texels_256 / 4,
                  "auto shades far fewer texels than 256 at 320x240: %s" % o["atlas"])

    # Async shading: d > 0 shades fewer texels than d = 0 with moving lights
    # (texels are counted in object space: a smaller image shows the same).
    # Whole tiles (the thesis's), which count objects. Timed frames 1 to 6
    # whatever the warm-up (frame k is a function of k alone): one job at
    # async distance 20 with no warm-up is the count, the purity check's
    # first image and the "seen" checks' whole tiles below.
    dyn = {"technique": "osl", "frames": 6, "warmup_frames": 0,
           "scene": {"width": 160, "height": 120, "dynamic": True},
           "osl": {"resolution": 32, "visibility": "all"}}
    pure = dict(dyn, async_distance=20, capture_interval=6)
    r_whole, p_whole = capture(d, pure, "whole")
    d20 = r_whole["osl"]
    d0 = d.run(dict(dyn, async_distance=0))["result"]["osl"]
    check(0 < d20["texels_shaded_per_frame"]["mean"] < d0["texels_shaded_per_frame"]["mean"],
          "async 20 shades fewer texels than async 0: %s vs %s" %
          (d20["texels_shaded_per_frame"], d0["texels_shaded_per_frame"]))
    check(d0["objects_reshaded_per_frame"]["max"] < 512,
          "only objects a moving light reaches are reshaded (%s)" % d0["objects_reshaded_per_frame"])
    # A count of objects: the smallest tiles show it as well as any.
    every = d.run(dict(dyn, async_distance=0, frames=1,
                       osl={"resolution": 8, "reshade": "all", "visibility": "all"}))
    check(every["result"]["osl"]["objects_reshaded_per_frame"]["mean"] == 512,
          "reshade=all reshades every object, as the thesis did")

    # Frame k is a pure function of k, even with stale (async) shading.
    _, b = capture(d, dict(pure, warmup_frames=7), "pure-b")
    diff = testlib.png_diff(p_whole, b)
    check(diff and diff["max_abs"] == 0, "frame 6 identical with 0 or 7 warm-up frames: %s" % diff)

    # Visibility "seen": only the atlas blocks the raster pass read (and
    # their neighbours) are shaded, each with the shading its schedule asks
    # for. The same pixels as whole tiles from fewer texels, frame k still a
    # pure function of k, nothing shaded for still lights after the first
    # frame, and a moving camera (marking with its own frame's view before
    # the selection) reads no stale block, at async distance 0 or 20. A
    # still camera at 32 texels (4x4 blocks a tile: seen shades half the
    # texels, against a quarter at 64, for a third of the CPU); the moving
    # camera at 64, where a block spans about a pixel on screen: at 32 it
    # spans several, and a one-block margin (the marking before issue 35)
    # would more often cover a frame's motion and hide its stale reads.
    seen = dict(pure, warmup_frames=2, osl={"resolution": 32, "visibility": "seen"})
    r_seen, p_seen = capture(d, seen, "seen")
    diff = testlib.png_diff(p_whole, p_seen)
    check(diff and diff["max_abs"] == 0, "seen gives whole tiles' pixels: %s" % diff)
    vis = r_seen.get("osl", {}).get("visibility", {})
    check(vis.get("mode") == "seen" and vis.get("stale_blocks") == 0,
          "a still camera reads no block with other shading: %s" % vis)
    t_whole = r_whole["osl"]["texels_shaded_per_frame"]["mean"]
    t_seen = r_seen["osl"]["texels_shaded_per_frame"]["mean"]
    check(0 < t_seen < 0.9 * t_whole, "seen shades fewer texels: %s vs %s" % (t_seen, t_whole))
    _, p_late = capture(d, dict(seen, warmup_frames=7), "seen-late")
    diff = testlib.png_diff(p_seen, p_late)
    check(diff and diff["max_abs"] == 0, "seen: frame 6 identical after 2 or 7 warm-up frames: %s"
          % diff)
    for path, dist in (("flythrough", 20), ("flythrough", 0), ("orbit", 0)):
        fly = d.run(dict(seen, frames=12, async_distance=dist, osl={"resolution": 64, "visibility": "seen"},
                         scene=dict(dyn["scene"], camera={"path": path, "period": 48})))
        fo = fly.get("result", {}).get("osl", {})
        check(fly["status"] == "done" and fo["visibility"]["stale_blocks"] == 0 and
              fo["staleness"]["reads"] > 0 and fo["staleness"]["unshaded_reads"] == 0 and
              (dist or fo["staleness"]["max"] == 0),
              "a %s (period 48) at async distance %d reads no stale block: %s, %s" %
              (path, dist, fo.get("visibility"), fo.get("staleness")))

    # Hidden objects are not reshaded: with a still camera the blocks read
    # are the first frame's, and no object without one is shaded later.
    cam = dict(dyn, async_distance=20, frames=8, warmup_frames=2, osl={})
    still_cam = d.run(cam)["result"]["osl"]
    vis = still_cam["visibility"]
    check(0 < vis["objects_reshaded"] <= vis["objects_read"] < 512 and
          vis["unread_objects_reshaded"] == 0,
          "defaults: objects never read (hidden) are never reshaded: %s" % vis)
    # Objects coming into view (an orbiting camera reads more of them) are
    # shaded before the first frame that reads them: no stale, no unshaded read.
    orbit = d.run(dict(cam, scene=dict(dyn["scene"], camera={"path": "orbit", "period": 360})))
    ovis = orbit["result"]["osl"]["visibility"]
    ost = orbit["result"]["osl"]["staleness"]
    check(ovis["objects_read"] > vis["objects_read"] and ovis["stale_blocks"] == 0 and
          ost["unshaded_reads"] == 0,
          "orbit: objects come into view shaded (%d objects read against %d, stale %d, "
          "unshaded %d)" % (ovis["objects_read"], vis["objects_read"], ovis["stale_blocks"],
                            ost["unshaded_reads"]))
    # Staleness stays within the schedule when nothing limits shading: a
    # block read shows the lights of at most (longest period - 1) frames ago.
    longest = max(int(p) for p in still_cam["objects_by_period"])
    st = still_cam["staleness"]
    check(st["reads"] > 0 and st["max"] <= longest - 1 and st["unshaded_reads"] == 0,
          "no budget: staleness within the longest period %d: %s" % (longest, st))
    # The budget holds every frame; what it leaves waits, and is counted.
    unlimited = still_cam["texels_shaded_per_frame"]["max"]
    budget = int(unlimited / 3) // 64 * 64
    cut = dict(cam, osl={"budget_texels": budget}, capture_interval=8)
    r_cut, p_cut = capture(d, cut, "budget-a")
    o = r_cut["osl"]
    check(o["budget"]["active"] and o["budget"]["overflow_frames"] == 0 and
          0 < o["texels_shaded_per_frame"]["max"] <= budget,
          "budget %d texels respected every frame: %s, %s" % (budget, o["texels_shaded_per_frame"],
                                                              o["budget"]))
    check(o["budget"]["deferred_blocks_per_frame"] > 0 and o["visibility"]["stale_blocks"] > 0
          and o["staleness"]["max"] > st["max"] and o["staleness"]["unshaded_reads"] == 0,
          "a tight budget defers blocks, reads them older, never unshaded: %s" % o["staleness"])
    _, p_again = capture(d, cut, "budget-b")
    diff = testlib.png_diff(p_cut, p_again)
    check(diff and diff["max_abs"] == 0, "a budget's cut is deterministic: %s" % diff)
    # A budget that allows what the frame needs changes nothing.
    roomy = d.run(dict(cam, osl={"budget_texels": int(unlimited) + 64}))["result"]["osl"]
    check(roomy["staleness"]["max"] <= longest - 1 and roomy["budget"]["deferred_blocks_per_frame"] == 0
          and roomy["texels_shaded_per_frame"] == still_cam["texels_shaded_per_frame"],
          "a budget that allows it: the same shading, staleness within the schedule: %s" %
          roomy["staleness"])
    # Change detection: a threshold no light's motion reaches keeps every
    # shading; 0 (the default) is off.
    kept = d.run(dict(cam, osl={"change_threshold": 1.0}))["result"]["osl"]
    check(kept["change"]["active"] and kept["change"]["reshades_saved_per_frame"] > 0 and
          kept["texels_shaded_per_frame"]["mean"] < still_cam["texels_shaded_per_frame"]["mean"],
          "change_threshold 1 saves reshades: %s" % kept["change"])
    check("change" not in still_cam, "change detection off by default")

    # The defaults (auto tiles, seen) agree with forward on a dynamic grid
    # at the thesis's async distance.
    ref = d.run({"technique": "osl", "async_distance": 20, "reference": "forward", "frames": 6,
                 "warmup_frames": 2, "capture_interval": 3,
                 "scene": {"preset": "grid", "dynamic": True, "width": 240, "height": 160}})
    ssim = ref.get("result", {}).get("quality", {}).get("worst_ssim", {}).get("value", 0)
    check(ref["status"] == "done" and ssim >= 0.999, "defaults: SSIM %.5f >= 0.999" % ssim)
    check(ref["spec"]["osl"]["resolution"] == "auto" and ref["spec"]["osl"]["visibility"] == "seen"
          and ref["spec"]["osl"]["budget_texels"] == 0 and ref["spec"]["osl"]["change_threshold"] == 0,
          "the defaults written back: %s" % ref["spec"]["osl"])

    # Bad OSL options name their field; an atlas too big fails the job clearly.
    for body, field in (({"technique": "osl", "osl": {"resolution": 100}}, "osl.resolution"),
                        ({"technique": "osl", "osl": {"resolution": "fine"}}, "osl.resolution"),
                        ({"technique": "osl", "async_distance": -1}, "async_distance"),
                        ({"technique": "osl", "osl": {"texel_density": -2}}, "osl.texel_density"),
                        ({"technique": "osl", "osl": {"rezolution": 64}}, "osl.rezolution"),
                        ({"technique": "osl", "osl": {"visibility": "some"}}, "osl.visibility"),
                        ({"technique": "osl", "osl": {"budget_texels": -1}}, "osl.budget_texels"),
                        ({"technique": "osl", "osl": {"budget_texels": 4096, "visibility": "all"}},
                         "osl.budget_texels"),
                        ({"technique": "osl", "osl": {"change_threshold": 2}}, "osl.change_threshold"),
                        ({"technique": "osl", "osl": {"change_threshold": 0.1, "visibility": "all"}},
                         "osl.change_threshold")):
        testlib.rejects(d, body, field)
    big = d.run({"technique": "osl", "frames": 1, "warmup_frames": 0, "scene": SCENE,
                 "osl": {"resolution": 1024}})
    check(big["status"] == "failed" and "atlas" in big.get("error", ""),
          "an atlas beyond the device fails with a clear message: %s" % big.get("error"))
    # The daemon serves on: seen with still lights, after the failed job.
    last = d.run(dict(seen, scene=dict(dyn["scene"], dynamic=False)))
    check(last["status"] == "done", "daemon serves on")
    still = last.get("result", {}).get("osl", {})
    check(still.get("texels_shaded_per_frame", {}).get("max") == 0 and
          still.get("visibility", {}).get("active") is False,
          "seen, still lights: nothing shaded after the first frame, and no marking: %s" % still)
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_osl")
