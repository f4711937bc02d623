"""Shared helpers for the end-to-end tests: a daemon on a free loopback
port, HTTP calls, and PNG checks through tests/tools/png-tool. Standard library
only, so the tests run on a bare Debian python3."""

import ctypes.util
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

SHADEBENCHD = os.environ.get("SHADEBENCHD", "./shadebenchd")
PNG_TOOL = os.environ.get("PNG_TOOL", "./tests/tools/png-tool")

failures = 0
checks = 0

# Time bounds in the tests are for the normal build. Under ASan and UBSan
# (make check in build-asan) every malloc is slower, the GL driver's and
# LLVM's included, so the bounds stretch by this factor: that run is for
# memory errors, not timings.
TIME_SCALE = float(os.environ.get("SHADEBENCH_TIME_SCALE") or
                   (10 if os.environ.get("SHADEBENCH_SANITIZERS") else 1))


# The frame bound (--max-frame-seconds, 2 s by default) refuses a job whose
# whole frame holds the render thread longer: on a 2-core box that others
# load twentyfold, an ordinary test job's frame can take that long. Every
# daemon the tests start (and --once, and the fleet's tasks) gets room
# through the environment; tests of the bound name their own with the flag,
# which wins.
os.environ.setdefault("SHADEBENCH_MAX_FRAME_SECONDS", "60")


def skip_without_egl():
    # Skipping is allowed only where EGL is entirely absent; .ci/run counts a
    # skip as a failure anyway.
    if ctypes.util.find_library("EGL") is None:
        print("SKIP: no libEGL on this machine")
        sys.exit(77)


def check(cond, what):
    global failures, checks
    checks += 1
    if not cond:
        failures += 1
        print("FAIL:", what, flush=True)
    return cond


def finish(name):
    """Exits 1 when a check failed, or when none was made (a test that
    checks nothing proves nothing)."""
    print("%s: %d checks, %d failed%s" % (name, checks, failures,
                                          "" if checks else " (no check was made: that fails)"))
    sys.exit(1 if failures or not checks else 0)


class Daemon:
    """shadebenchd on 127.0.0.1 with a free port and its own state dir."""

    def __init__(self, *args, env=None):
        self.tmp = tempfile.mkdtemp(prefix="shadebench-test-")
        self.state = os.path.join(self.tmp, "state")
        port_file = os.path.join(self.tmp, "port")
        self.log_path = os.path.join(self.tmp, "daemon.log")
        self.log = open(self.log_path, "w")
        full_env = dict(os.environ)
        full_env.update(env or {})
        self.proc = subprocess.Popen(
            [SHADEBENCHD, "--listen", "127.0.0.1:0", "--port-file", port_file,
             "--state-dir", self.state] + list(args),
            stdout=self.log, stderr=subprocess.STDOUT, env=full_env)
        deadline = time.time() + 60 * TIME_SCALE
        while not os.path.exists(port_file):
            if self.proc.poll() is not None or time.time() > deadline:
                self.dump_log()
                raise RuntimeError("shadebenchd did not start")
            time.sleep(0.05)
        with open(port_file) as f:
            self.port = int(f.read())
        self.base = "http://127.0.0.1:%d" % self.port

    def dump_log(self):
        if not self.log.closed:
            self.log.flush()
        with open(self.log_path) as f:
            text = f.read()
        # A crash report (common/crash_report.h) whole, with what led to it.
        crash = text.rfind(": fatal SIG")
        start = max(0, min(len(text) - 6000, crash - 3000)) if crash >= 0 else len(text) - 6000
        sys.stdout.write(text[max(0, start):])

    def alive(self):
        return self.proc.poll() is None

    def stop(self):
        """SIGTERM; returns the exit code (0 expected)."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=60 * TIME_SCALE)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.log.close()
        return self.proc.returncode

    def restarted(self, *args, **kw):
        """A fresh daemon over this one's state directory (stopped first, if
        it still runs); this one's files stay until its cleanup."""
        if self.alive():
            self.stop()
        return Daemon("--state-dir", self.state, *args, **kw)

    def cleanup(self, keep=False):
        if not keep:
            shutil.rmtree(self.tmp, ignore_errors=True)

    def request(self, method, path, body=None, headers=None, timeout=120 * TIME_SCALE):
        data = body
        if isinstance(body, (dict, list)):
            data = json.dumps(body).encode()
        elif isinstance(body, str):
            data = body.encode()
        req = urllib.request.Request(self.base + path, data=data, method=method,
                                     headers=headers or {})
        try:
            with urllib.request.urlopen(req, timeout=timeout) as resp:
                return resp.status, dict(resp.headers), resp.read()
        except urllib.error.HTTPError as e:
            return e.code, dict(e.headers), e.read()

    def json(self, method, path, body=None, **kw):
        status, headers, raw = self.request(method, path, body, **kw)
        try:
            return status, json.loads(raw)
        except ValueError:
            return status, {"_raw": raw.decode(errors="replace")}

    def submit(self, job):
        status, body = self.json("POST", "/v1/jobs", job)
        if status != 202:
            raise RuntimeError("submit failed: %d %s" % (status, body))
        return body["id"]

    def wait(self, job_id, timeout=600 * TIME_SCALE):
        deadline = time.time() + timeout
        while True:
            status, body = self.json("GET", "/v1/jobs/%s?wait=60" % job_id)
            if body.get("status") not in ("queued", "running") or time.time() > deadline:
                return body

    def run(self, job):
        return self.wait(self.submit(job))

    def wait_sweep(self, sweep_id, timeout=900 * TIME_SCALE):
        deadline = time.time() + timeout
        while True:
            status, body = self.json("GET", "/v1/sweeps/%s?wait=30" % sweep_id)
            if body.get("status") not in ("queued", "running") or time.time() > deadline:
                return body

    def download(self, path, dest):
        status, _, raw = self.request("GET", path)
        if status == 200:
            with open(dest, "wb") as f:
                f.write(raw)
        return status


def fill_disk(path):
    """Appends zeros to path until its disk is full."""
    try:
        with open(path, "ab") as f:
            while True:
                f.write(b"\0" * 65536)
                f.flush()
    except OSError:
        pass


def rejects(d, body, field, status=400, what=None):
    """POST body as a job; it must be refused with status, naming field."""
    code, reply = d.json("POST", "/v1/jobs", body)
    err = reply.get("error", {}) if isinstance(reply, dict) else {}
    return check(code == status and err.get("field") == field and len(err.get("message", "")) > 5,
                 "%s -> %d naming %r (got %d %s)" % (what or body, status, field, code, reply))


def stop_and_check(d):
    """SIGTERM the daemon, which must exit 0; keep its files if anything failed."""
    code = d.stop()
    check(code == 0, "daemon exits 0 on SIGTERM (got %s)" % code)
    if failures:
        d.dump_log()
    d.cleanup(keep=failures > 0)


def png_info(path):
    out = subprocess.run([PNG_TOOL, "info", path], capture_output=True, text=True)
    return json.loads(out.stdout) if out.returncode == 0 else None


def png_diff(a, b):
    out = subprocess.run([PNG_TOOL, "diff", a, b], capture_output=True, text=True)
    return json.loads(out.stdout) if out.returncode == 0 else None


def png_pixels(path):
    """(width, height, [(r, g, b), ...] row-major, top row first) of an 8-bit
    RGB or RGBA, non-interlaced PNG (what the daemon writes), decoded with
    the standard library alone, for tests that read single pixels."""
    import struct
    import zlib
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("%s: not a PNG" % path)
    pos, idat, w = 8, b"", 0
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or ctype not in (2, 6) or interlace:
                raise ValueError("%s: only 8-bit RGB/RGBA, non-interlaced" % path)
            bpp = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = w * bpp
    prev = bytearray(stride)
    pixels = []
    for y in range(h):
        ftype = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if ftype == 1:
                line[i] = (line[i] + a) & 255
            elif ftype == 2:
                line[i] = (line[i] + b) & 255
            elif ftype == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif ftype == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pred) & 255
        pixels.extend(tuple(line[x * bpp:x * bpp + 3]) for x in range(w))
        prev = line
    return w, h, pixels


def sphere_shadow_counts(camera, off, on, w, h, towards):
    """The sphere preset's shadow, ray-cast: a sphere of radius 0.8 at the
    origin on the ground at y -0.8, seen by camera (result.scene.camera),
    off and on the w x h frames without and with shadows (png_pixels' pixel
    lists), towards(p) the unit direction from p to the light and how far it
    is. Returns (core, core_dark, outside_changed, lit_changed): ground
    pixels the sphere surely hides from the light and how many of those are
    darker with shadows, ground pixels no shadow can reach that changed,
    and pixels on the sphere's lit side that changed (acne)."""
    import math
    eye, target = camera["eye_at_frame_0"], camera["target_at_frame_0"]

    def unit(v):
        n = math.sqrt(sum(c * c for c in v))
        return [c / n for c in v]
    fwd = unit([t - e for t, e in zip(target, eye)])
    right = unit([-fwd[2], 0.0, fwd[0]])
    up = [right[1] * fwd[2] - right[2] * fwd[1], right[2] * fwd[0] - right[0] * fwd[2],
          right[0] * fwd[1] - right[1] * fwd[0]]
    tan_half = math.tan(math.radians(camera["fovy_deg"]) / 2)

    def shaded(g, r):
        # The path from g to the light passes within r of the centre.
        L, far = towards(g)
        t = min(max(-sum(a * c for a, c in zip(g, L)), 0.0), far)
        return math.sqrt(sum((a + t * c) ** 2 for a, c in zip(g, L))) < r

    core = core_dark = outside_changed = lit_changed = 0
    for y in range(h):
        for x in range(w):
            sx = (2 * (x + 0.5) / w - 1) * tan_half * w / h
            sy = (1 - 2 * (y + 0.5) / h) * tan_half
            dvec = unit([f + sx * r + sy * u for f, r, u in zip(fwd, right, up)])
            a, b = sum(off[y * w + x]) / 3.0, sum(on[y * w + x]) / 3.0
            bb = sum(e * c for e, c in zip(eye, dvec))
            disc = bb * bb - (sum(e * e for e in eye) - 0.64)
            t = None if disc < 0 else -bb - math.sqrt(disc)
            if t is not None and t > 0:
                p = [e + t * c for e, c in zip(eye, dvec)]
                if sum(q * c for q, c in zip(p, towards(p)[0])) / 0.8 > 0.3 and abs(a - b) > 2:
                    lit_changed += 1
                continue
            if dvec[1] >= 0:
                continue
            t = (-0.8 - eye[1]) / dvec[1]
            g = [e + t * c for e, c in zip(eye, dvec)]
            if abs(g[0]) > 5.5 or abs(g[2]) > 5.5:
                continue
            if shaded(g, 0.8 * 0.85):
                core += 1
                core_dark += b <= 0.6 * a
            elif not shaded(g, 0.8 * 1.15 + 0.05) and abs(a - b) > 2:
                outside_changed += 1
    return core, core_dark, outside_changed, lit_changed


def towards_point(light):
    """sphere_shadow_counts' towards for a light at a point."""
    import math

    def towards(p):
        v = [a - b for a, b in zip(light, p)]
        n = math.sqrt(sum(c * c for c in v))
        return [c / n for c in v], n
    return towards
