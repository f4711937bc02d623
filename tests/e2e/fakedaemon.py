"""A scripted stand-in for shadebenchd's job API, for tests of the client's
own logic: the verdicts it draws from given run times and interference
figures, its JUnit, its log and its usage errors. No GL and no timing: each
job's result comes from a function of the test, so a case such as "the
runs confirming a regression were all noisy" is made exactly, never hoped
for from a busy machine. The real daemon's shapes (GET /v1/jobs/ID,
/v1/info, the job list, sweeps) are kept to what the client reads.
Standard library only."""

import json
import threading
import urllib.parse
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

LLVMPIPE = {"gl_renderer": "llvmpipe (LLVM 15.0.6, 256 bits)", "gl_version": "4.5 (Core Profile) Mesa 22.3.6",
            "glsl_version": "4.50", "egl_device": "fake", "egl_platform": "device"}
TECHNIQUES = ("forward", "unlit", "deferred", "osl")


def stats(ms):
    return {"n": 10, "mean": ms, "median": ms, "p95": ms * 1.05, "median_ci95": [ms * 0.98, ms * 1.02]}


def result(ms, share=0.02, captures=None):
    """A finished job's result: frame_ms (and the other series) at ms, other
    processes' share of the CPU during the timed region, and captures."""
    return {"frame_ms": stats(ms), "gpu_ms": stats(ms * 0.9), "cpu_ms": stats(ms * 0.2),
            "fps": 1000.0 / ms, "wall_s": ms / 100.0, "device": LLVMPIPE,
            "interference": {"other_cpu_share": share, "noisy": share > 0.10, "cpus": 2,
                             "loadavg_start": [1.0, 1.0, 1.0], "loadavg_end": [1.0, 1.0, 1.0]},
            "captures": captures or []}


class FakeDaemon:
    """outcome(spec, n) -> (status, result or error) for the n-th job
    submitted (from 0), spec as posted. Each job answers "running" to
    `polls` GETs before it ends. hold: a set of job numbers whose GET waits
    until release() (to see what the client wrote before it)."""

    def __init__(self, outcome, polls=2):
        self.outcome = outcome
        self.polls = polls
        self.jobs = {}
        self.order = []
        self.sweeps = {}
        self.lock = threading.Lock()
        self.hold = set()
        self.released = threading.Event()
        self.requests = []
        daemon = self

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *args):
                pass

            def reply(self, status, body):
                data = json.dumps(body).encode() if not isinstance(body, bytes) else body
                self.send_response(status)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

            def do_GET(self):
                daemon.requests.append(("GET", self.path))
                self.reply(*daemon.get(self.path))

            def do_POST(self):
                n = int(self.headers.get("Content-Length") or 0)
                body = json.loads(self.rfile.read(n) or b"{}")
                daemon.requests.append(("POST", self.path))
                self.reply(*daemon.post(self.path, body))

            def do_DELETE(self):
                daemon.requests.append(("DELETE", self.path))
                job = daemon.jobs.get(self.path.rsplit("/", 1)[-1])
                if job:
                    job["status"] = "cancelled"
                self.reply(200 if job else 404, job or {"error": {"field": "id", "message": "no such job"}})

        self.server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.base = "http://127.0.0.1:%d" % self.server.server_address[1]
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)
        self.thread.start()

    def stop(self):
        self.released.set()
        self.server.shutdown()
        self.server.server_close()

    def release(self):
        self.released.set()

    def submitted(self):
        return len(self.order)

    def post(self, path, body):
        with self.lock:
            if path == "/v1/sweeps":
                # outcome(body, "sweep") -> [(technique, values, ms)]: each
                # point a finished job.
                sid = "sweep-%04d" % (len(self.sweeps) + 1)
                points = []
                for tech, values, ms in self.outcome(body, "sweep"):
                    jid = "%s-point-%d" % (sid, len(points))
                    self.jobs[jid] = {"id": jid, "n": -1, "status": "done", "technique": tech,
                                      "spec": dict(body.get("base", {}), technique=tech), "gets": 0,
                                      "created": "2026-11-27T00:00:00.000Z",
                                      "started": "2026-11-27T00:00:00.000Z",
                                      "finished": "2026-11-27T00:00:01.000Z",
                                      "progress": {"frames_done": 1, "frames_total": 1},
                                      "result": result(ms)}
                    points.append({"technique": tech, "values": values, "status": "done", "job": jid,
                                   "frame_ms": stats(ms), "gpu_ms": stats(ms), "cpu_ms": stats(ms),
                                   "wall_s": {"mean": 1.0}})
                self.sweeps[sid] = {"id": sid, "status": "done", "kind": "vary", "points": points,
                                    "progress": {"points_done": len(points), "points_total": len(points)},
                                    "result": {}}
                return 202, {"id": sid}
            n = len(self.order)
            jid = "20261127-000000-%04d" % (n + 1)
            spec = dict(body)
            spec.setdefault("technique", "forward")
            job = {"id": jid, "n": n, "status": "queued", "technique": spec["technique"], "spec": spec,
                   "labels": spec.get("labels", {}), "gets": 0,
                   "created": "2026-11-27T00:00:%02d.000Z" % (n % 60),
                   "progress": {"frames_done": 0, "frames_total": spec.get("frames", 10)}}
            self.jobs[jid] = job
            self.order.append(jid)
            return 202, {"id": jid, "status": "queued"}

    def get(self, path):
        url = urllib.parse.urlparse(path)
        query = dict(urllib.parse.parse_qsl(url.query))
        if url.path == "/v1/info":
            return 200, {"name": "shadebenchd", "version": "fake", "api": "1", "device": LLVMPIPE,
                         "techniques": [{"name": t, "summary": t, "options": {}} for t in TECHNIQUES],
                         "effects": [], "limits": {}, "sweepable": {}}
        if url.path == "/v1/jobs":
            return 200, {"jobs": [self.entry(self.jobs[j]) for j in self.order
                                  if self.matches(self.jobs[j], query)]}
        if url.path.startswith("/v1/sweeps/"):
            sw = self.sweeps.get(url.path.rsplit("/", 1)[-1])
            return (200, sw) if sw else (404, {"error": {"field": "id", "message": "no such sweep"}})
        if url.path.startswith("/v1/jobs/"):
            job = self.jobs.get(url.path.split("/")[3])
            if not job:
                return 404, {"error": {"field": "id", "message": "no such job"}}
            if job["n"] in self.hold and not self.released.wait(30):
                return 500, {"error": {"field": "", "message": "never released"}}
            with self.lock:
                self.advance(job)
                return 200, {k: v for k, v in job.items() if k not in ("n", "gets")}
        return 404, {"error": {"field": "path", "message": "not faked"}}

    def advance(self, job):
        if job["status"] in ("done", "failed", "cancelled"):
            return
        job["gets"] += 1
        total = job["progress"]["frames_total"]
        if job["gets"] <= self.polls:
            job["status"] = "running"
            job["phase"] = "timed"
            job["progress"]["frames_done"] = total * job["gets"] // (self.polls + 1)
            return
        status, res = self.outcome(job["spec"], job["n"])
        job["status"] = status
        job["progress"]["frames_done"] = total
        job["finished"] = "2026-11-27T00:01:%02d.000Z" % (job["n"] % 60)
        if status == "done":
            job["result"] = res
        else:
            job["error"] = res

    def matches(self, job, query):
        if job["status"] != query.get("status", "done"):
            return False
        return "technique" not in query or job["technique"] == query["technique"]

    def entry(self, job):
        res = job.get("result", {})
        figures = {k: {"median": res[k]["median"], "ci95": res[k]["median_ci95"]}
                   for k in ("frame_ms", "gpu_ms", "cpu_ms") if k in res}
        figures["gl_renderer"] = LLVMPIPE["gl_renderer"]
        return {"id": job["id"], "status": job["status"], "technique": job["technique"],
                "created": job["created"], "labels": job["labels"], "figures": figures}
