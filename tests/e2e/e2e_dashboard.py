"""The dashboard in a real browser (headless Chromium over the DevTools
pipe, tests/e2e/browserlib.py), against a daemon with finished jobs, a
running job, a sweep and an uploaded asset, and a second daemon with a
token: every page loads with no console message; the job list pages and
filters; a job's image comparison shows both images, its swipe slider
moves, F flips A and B, the difference view changes with the contrast
control, the magnifier follows in both panels and the worst SSIM window is
found; the running job's progress advances and its cancel works; the
sweep's chart opens a point's job; an asset is uploaded from the page;
the token-protected daemon asks for the token and then works.
With SHADEBENCH_DASHBOARD_SHOTS=DIR it leaves a screenshot of each page
there (docs/dashboard/ holds the committed ones)."""

import json
import os
import sys
import tempfile
import time

import browserlib
import testlib
from testlib import check

testlib.skip_without_egl()
SHOTS = os.environ.get("SHADEBENCH_DASHBOARD_SHOTS")
if SHOTS:
    os.makedirs(SHOTS, exist_ok=True)
SCENE = {"dynamic": True, "width": 160, "height": 120, "sphere_segments": 8}
T = testlib.TIME_SCALE


def shot(b, name):
    if SHOTS:
        b.screenshot(os.path.join(SHOTS, name + ".png"))


def ready(b, url, what):
    """Navigates and waits for the page's router to finish rendering."""
    b.goto(url)
    b.wait("document.body.dataset.ready === location.hash && !document.querySelector('main p.error')",
           60, what)


def canvas_sum(b, selector):
    """The sum of a canvas's RGB bytes (how bright what it shows is)."""
    return b.eval("(() => { const c = document.querySelector(%s); const d = c.getContext('2d')"
                  ".getImageData(0, 0, c.width, c.height).data; let s = 0;"
                  " for (let i = 0; i < d.length; i += 4) s += d[i] + d[i + 1] + d[i + 2]; return s; })()"
                  % json.dumps(selector))


def canvas_equals_image(b, selector, url):
    """Does the canvas show exactly the image at url (fetched with the page's token)?"""
    return b.eval("""(async () => {
        const api = await import('/ui/api.js');
        const img = await api.image(%s);
        const c = document.createElement('canvas'); c.width = img.naturalWidth; c.height = img.naturalHeight;
        const x = c.getContext('2d'); x.drawImage(img, 0, 0);
        const a = x.getImageData(0, 0, c.width, c.height).data;
        const v = document.querySelector(%s);
        const b = v.getContext('2d').getImageData(0, 0, v.width, v.height).data;
        if (a.length !== b.length) return false;
        for (let i = 0; i < a.length; i++) if (a[i] !== b[i]) return false;
        return true; })()""" % (json.dumps(url), json.dumps(selector)))


d = testlib.Daemon()
token_daemon = None
b = None
try:
    # The finished jobs, a sweep (its reference timed), then a running job.
    forward = d.submit({"technique": "forward", "frames": 4, "warmup_frames": 1, "capture_interval": 4,
                        "scene": SCENE, "labels": {"branch": "main"}})
    osl = d.submit({"technique": "osl", "frames": 4, "warmup_frames": 1, "capture_interval": 4,
                    "osl": {"resolution": "auto"}, "reference": "forward", "scene": SCENE,
                    "labels": {"branch": "main"}})
    status, reply = d.json("POST", "/v1/sweeps", {
        "base": {"technique": "osl", "frames": 3, "warmup_frames": 1, "capture_interval": 3,
                 "osl": {"resolution": "auto"}, "reference": "forward",
                 "scene": dict(SCENE, width=96, height=64)},
        "vary": {"async_distance": [0, 20]}})
    check(status == 202, "sweep accepted: %s" % reply)
    sweep_id = reply["id"]
    for job_id in (forward, osl):
        check(d.wait(job_id)["status"] == "done", "job %s done" % job_id)
    sw = d.wait_sweep(sweep_id)
    check(sw["status"] == "done", "sweep done")
    long_job = d.submit({"technique": "forward", "frames": 1000000, "warmup_frames": 0, "timeout_s": 0,
                         "scene": {"width": 32, "height": 24, "sphere_segments": 8}})
    deadline = time.time() + 60 * T
    while d.json("GET", "/v1/jobs/" + long_job)[1]["progress"]["frames_done"] < 1 and time.time() < deadline:
        time.sleep(0.1)

    # The daemon serves the dashboard's files, the charting library among them.
    status, headers, raw = d.request("GET", "/")
    check(status == 200 and b"/ui/app.js" in raw and headers.get("Content-Type", "").startswith("text/html"),
          "/ is the dashboard's page")
    status, headers, raw = d.request("GET", "/ui/vendor/dygraph.min.js")
    check(status == 200 and b"Dygraph" in raw, "dygraphs is embedded")
    status, _, _ = d.request("GET", "/ui/nothing.js")
    check(status == 404, "an unknown dashboard file is a 404")

    b = browserlib.Browser(width=1300, height=1000, time_scale=T)

    # Jobs: every job, newest first, the running one with its progress.
    ready(b, d.base + "/#/jobs", "the job list")
    ids = b.eval("[...document.querySelectorAll('#job-list tbody tr')].map((r) => r.dataset.id)")
    check(ids[0] == long_job and forward in ids and osl in ids and len(ids) == 6,
          "the list shows the 6 jobs, newest first: %s" % ids)
    check(b.wait("document.querySelector('#job-list tr[data-status=running] progress')", 10, "progress bar"),
          "the running job has a progress bar")
    shot(b, "jobs")
    # Pages of 2: three pages, each its own jobs.
    ready(b, d.base + "/#/jobs?limit=2", "the first page of 2")
    seen = []
    for page in range(3):
        rows = b.eval("[...document.querySelectorAll('#job-list tbody tr')].map((r) => r.dataset.id)")
        check(len(rows) == 2, "page %d has 2 jobs" % (page + 1))
        seen += rows
        has_next = b.eval("!!document.getElementById('next-page')")
        check(has_next == (page < 2), "page %d %s a next page" % (page + 1, "has" if page < 2 else "has no"))
        if has_next:
            x, y = b.center("#next-page")[:2]
            before = b.eval("location.hash")
            b.click(x, y)
            b.wait("location.hash !== %s && document.body.dataset.ready === location.hash" % json.dumps(before),
                   30, "the next page")
    check(sorted(seen) == sorted(ids), "the pages hold every job once")
    # Filters: technique and status from the form.
    ready(b, d.base + "/#/jobs", "the job list")
    b.eval("(() => { const f = document.getElementById('job-filters'); f.technique.value = 'osl';"
           " f.status.value = 'done'; f.requestSubmit(); })()")
    b.wait("location.hash.includes('technique=osl') && document.body.dataset.ready === location.hash", 30,
           "the filtered list")
    techs = b.eval("[...document.querySelectorAll('#job-list tbody tr')].map((r) => r.children[3].textContent)")
    check(techs and all(t == "osl" for t in techs) and len(techs) == 3, "technique=osl lists the 3 OSL jobs: %s" % techs)
    ready(b, d.base + "/#/jobs?label.branch=main", "the label filter")
    rows = b.eval("[...document.querySelectorAll('#job-list tbody tr')].map((r) => r.dataset.id)")
    check(sorted(rows) == sorted([forward, osl]), "label.branch=main lists the two labelled jobs")

    # A job: headline, noise verdict, charts, and the image comparison.
    ready(b, d.base + "/#/job/" + osl, "the OSL job's page")
    b.wait("document.querySelectorAll('.imgcmp canvas.view').length === 2 && "
           "!!(document.querySelector('.frame-times') && document.querySelector('.frame-times').dygraph)", 60,
           "the comparison and the frame-time chart")
    check(b.eval("document.querySelector('.headline [data-figure=frame_ms] .value').textContent.endsWith('ms')"),
          "the headline shows frame_ms")
    check(b.eval("!!document.querySelector('.verdict')"), "the noise verdict is shown")
    job = d.json("GET", "/v1/jobs/" + osl)[1]
    cap = job["result"]["captures"][0]
    check(canvas_equals_image(b, ".imgcmp .panel:nth-child(1) canvas.view", cap["url"]) and
          canvas_equals_image(b, ".imgcmp .panel:nth-child(2) canvas.view", cap["reference_url"]),
          "side by side shows the capture and its reference, pixel for pixel")
    # The magnifier follows the pointer in both panels.
    x, y, left, top, w, h = b.center(".imgcmp .panel:nth-child(1) canvas.view")
    b.move(left + w * 0.3, top + h * 0.4)
    lenses = b.wait("[...document.querySelectorAll('.imgcmp canvas.lens')].filter((l) => !l.hidden).length", 10,
                    "the magnifier")
    check(lenses == 2, "the magnifier shows in both panels")
    shot(b, "job")
    # The worst SSIM window.
    b.eval("document.querySelector('.imgcmp button.worst').click()")
    worst = job["result"]["captures"][0]["metrics"]["ssim_min"]
    check(b.eval("document.querySelector('.imgcmp').dataset.lens") == "%d,%d" % (worst["x"], worst["y"]),
          "the worst SSIM window's button centres the magnifier on it")
    # Swipe: the slider follows a click on the image.
    b.eval("document.querySelector('.imgcmp button[data-view=swipe]').click()")
    b.wait("document.querySelector('.imgcmp').dataset.view === 'swipe'", 10, "the swipe view")
    start = int(b.eval("document.querySelector('.imgcmp .panel').dataset.swipe"))
    x, y, left, top, w, h = b.center(".imgcmp canvas.view")
    b.click(left + w * 0.2, top + h / 2)
    moved = int(b.eval("document.querySelector('.imgcmp .panel').dataset.swipe"))
    check(start == 80 and abs(moved - 32) <= 2, "the swipe line moved from 80 to about 32: %d" % moved)
    check(abs(float(b.eval("document.querySelector('.imgcmp input.swipe').value")) - 0.2) < 0.02,
          "the slider shows where the line is")
    # Flip: F swaps A and B.
    b.eval("document.querySelector('.imgcmp button[data-view=flip]').click()")
    b.wait("document.querySelector('.imgcmp').dataset.view === 'flip'", 10, "the flip view")
    shown_a = b.eval("document.querySelector('.imgcmp').dataset.showing")
    check(canvas_equals_image(b, ".imgcmp canvas.view", cap["url"]), "flip starts on A")
    b.eval("document.querySelector('.imgcmp').focus()")
    b.key("f", "KeyF", 70)
    b.wait("document.querySelector('.imgcmp').dataset.showing !== %s" % json.dumps(shown_a), 10, "the flip")
    check(canvas_equals_image(b, ".imgcmp canvas.view", cap["reference_url"]), "F shows B, the reference")
    b.key("f", "KeyF", 70)
    b.wait("document.querySelector('.imgcmp').dataset.showing === 'A'", 10, "the flip back")
    # Difference views: contrast brightens the absolute difference and the FLIP map.
    for kind in ("abs", "flip", "ssim"):
        b.eval("(() => { const s = document.querySelector('.imgcmp select.diff-kind'); s.value = %s;"
               " s.dispatchEvent(new Event('change')); })()" % json.dumps(kind))
        b.wait("document.querySelector('.imgcmp .panel') && document.querySelector('.imgcmp .panel').dataset.kind === %s"
               % json.dumps(kind), 20, "the %s view" % kind)
        b.eval("(() => { const g = document.querySelector('.imgcmp input.contrast'); g.value = 0;"
               " g.dispatchEvent(new Event('input')); })()")
        b.wait("document.querySelector('.imgcmp .panel').dataset.gain === '1'", 20, "contrast 1")
        low = canvas_sum(b, ".imgcmp canvas.view")
        b.eval("(() => { const g = document.querySelector('.imgcmp input.contrast'); g.value = 4;"
               " g.dispatchEvent(new Event('input')); })()")
        b.wait("document.querySelector('.imgcmp .panel').dataset.gain === '16'", 20, "contrast 16")
        high = canvas_sum(b, ".imgcmp canvas.view")
        # The SSIM map is white where equal: contrast darkens its shortfall.
        check(high < low if kind == "ssim" else high > low,
              "the %s view changes with the contrast: %d at x1, %d at x16" % (kind, low, high))
        if kind == "flip":
            shot(b, "job-flip")
    # PerceptualDiff's mask: the API makes it, as many failing pixels as the job counted.
    status, headers, raw = d.request("GET", cap["pdiff_mask_url"])
    check(status == 200 and raw[:8] == b"\x89PNG\r\n\x1a\n" and
          int(headers.get("X-Failing-Pixels", -1)) == cap["metrics"]["pdiff"]["failing_pixels"],
          "the PerceptualDiff mask counts the job's failing pixels (%s)" % headers.get("X-Failing-Pixels"))

    # The running job: its progress advances, then the page cancels it.
    ready(b, d.base + "/#/job/" + long_job, "the running job")
    first = b.wait("document.querySelector('.live progress') && document.querySelector('.live .progress-text')"
                   ".textContent", 30, "the progress")
    later = b.wait("(() => { const t = document.querySelector('.live .progress-text');"
                   " return t && t.textContent !== %s && t.textContent; })()" % json.dumps(first), 30,
                   "the progress to advance")
    check(int(later.split("/")[0]) > int(first.split("/")[0]), "progress advanced: %s then %s" % (first, later))
    check(b.wait("document.querySelector('.live .eta') && document.querySelector('.live .eta').textContent", 30,
                 "the time left").endswith("left"), "the time left is shown")
    shot(b, "job-running")
    b.eval("document.getElementById('cancel-job').click()")
    b.wait("document.querySelector('.job-head .badge').textContent === 'cancelled'", 60, "the cancel")
    check(d.json("GET", "/v1/jobs/" + long_job)[1]["status"] == "cancelled", "the page cancelled the job")

    # Two jobs compared.
    ready(b, d.base + "/#/compare?a=%s&b=%s" % (forward, osl), "the comparison of two jobs")
    b.wait("document.querySelectorAll('.imgcmp canvas.view').length === 2", 60, "both frames")
    check(b.eval("document.querySelectorAll('.compare-figures tbody tr').length") >= 6, "figures side by side")
    shot(b, "compare")

    # The sweep: the summary first, and a click on a chart point opens its job.
    ready(b, d.base + "/#/sweep/" + sweep_id, "the sweep")
    b.wait("!!(document.querySelector('.speed-accuracy') && document.querySelector('.speed-accuracy').dygraph)", 30,
           "the speed-accuracy chart")
    check(b.eval("document.querySelectorAll('#sweep-summary tbody tr').length") == 1, "one workload summarised")
    check(b.eval("document.querySelectorAll('#sweep-points tbody tr').length") == 3, "the table has the 3 points")
    shot(b, "sweep")
    target = b.eval("""(() => { const box = document.querySelector('.speed-accuracy'); box.scrollIntoView({block: 'center'});
        const g = box.dygraph, p = box.points.find((q) => q.series === 'osl');
        const [cx, cy] = g.toDomCoords(p.x, p.y); const r = g.graphDiv.getBoundingClientRect();
        return [r.left + cx, r.top + cy, p.job]; })()""")
    b.move(target[0], target[1])
    b.click(target[0], target[1])
    b.wait("location.hash === '#/job/%s' && document.body.dataset.ready === location.hash" % target[2], 30,
           "the point's job")
    check(True, "a click on the chart opened the point's job %s" % target[2])

    # History of the OSL job's workload.
    ready(b, d.base + "/#/history?job=" + osl, "the history")
    check(b.eval("!!document.getElementById('history-changes')"), "the history lists the gate's changes")
    shot(b, "history")

    # Assets: an upload from the page, then its description.
    ready(b, d.base + "/#/assets", "the assets")
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import gltf_gen
    g = gltf_gen.Gltf()
    g.node(mesh=g.mesh(gltf_gen.cube()), name="cube")
    path = os.path.join(d.tmp, "cube.glb")
    with open(path, "wb") as f:
        f.write(g.glb())
    obj = b.send("Runtime.evaluate", {"expression": "document.querySelector('#upload-form input[type=file]')"})
    b.send("DOM.setFileInputFiles", {"files": [path], "objectId": obj["result"]["objectId"]})
    b.eval("(() => { const i = document.querySelector('#upload-form input[type=file]');"
           " i.dispatchEvent(new Event('change')); document.getElementById('upload-form').requestSubmit(); })()")
    b.wait("location.hash === '#/asset/cube.glb' && document.body.dataset.ready === location.hash", 120,
           "the uploaded asset's page")
    check(b.eval("document.querySelector('main h1').textContent") == "Asset cube.glb", "the asset's page")
    reference = d.json("GET", "/v1/info")[1].get("reference", {})
    check(b.eval("!!document.getElementById('fidelity-form')") == bool(reference.get("available")),
          "the asset's page offers the Khronos comparison exactly when the daemon has the reference")
    ready(b, d.base + "/#/assets", "the assets")
    check(b.eval("[...document.querySelectorAll('#asset-list tbody tr')].map((r) => r.dataset.name)") == ["cube.glb"],
          "the list shows the upload")
    shot(b, "assets")
    check(not b.console, "no console message on any page: %s" % b.console[:5])

    # A daemon with a token: the page asks for it, then works.
    token_file = os.path.join(d.tmp, "token")
    with open(token_file, "w") as f:
        f.write("s3cret-token\n")
    token_daemon = testlib.Daemon("--token", token_file)
    status, _, _ = token_daemon.request("GET", "/v1/jobs")
    check(status == 401, "the API needs the token")
    status, _, _ = token_daemon.request("GET", "/ui/app.js")
    check(status == 200, "the dashboard's files do not")
    b.goto(token_daemon.base + "/#/jobs")
    b.wait("document.getElementById('token-dialog').open", 30, "the token dialog")
    shot(b, "token")
    b.eval("document.getElementById('token-input').focus()")
    b.type_text("wrong")
    b.eval("document.getElementById('token-form').requestSubmit()")
    b.wait("document.getElementById('token-dialog').open && "
           "document.getElementById('token-error').textContent.includes('refused')", 30, "a wrong token refused")
    b.eval("document.getElementById('token-input').value = ''; document.getElementById('token-input').focus()")
    b.type_text("s3cret-token")
    b.eval("document.getElementById('token-form').requestSubmit()")
    b.wait("document.body.dataset.ready === '#/jobs' && document.getElementById('job-list')", 30,
           "the job list with the token")
    check(not b.eval("document.getElementById('token-dialog').open"), "the dialog closed")
    # The browser's own 401 lines are the protocol at work, not the page's errors.
    errors = [m for m in b.console if "401" not in m]
    check(not errors, "no console message but the 401s: %s" % errors[:5])
finally:
    if b:
        b.close()
    if token_daemon:
        testlib.stop_and_check(token_daemon)
    testlib.stop_and_check(d)

testlib.finish("e2e_dashboard")
