"""The unit's hardening options tried on the daemon and llvmpipe without
systemd as init: tests/tools/sandbox-run loads the seccomp rules systemd
would load for each option the unit sets (SystemCallFilter as an
allow-list expanded by systemd-analyze, RestrictAddressFamilies,
RestrictRealtime, RestrictNamespaces, LockPersonality), and a private
/proc mounted with hidepid=invisible,subset=pid stands for ProtectProc= and
ProcSubset=. Each option alone, then all together with the HTTP side serving
a job, must leave the daemon working; MemoryDenyWriteExecute, which the unit
leaves out, must break it (the reason the unit gives)."""

import os
import shutil
import subprocess
import sys
import tempfile
import time

import testlib
from testlib import check

testlib.skip_without_egl()

UNIT = os.environ.get("SHADEBENCH_UNIT", "systemd/shadebenchd.service")
SANDBOX = os.environ.get("SANDBOX_RUN", "./tests/tools/sandbox-run")
if not os.path.exists(SANDBOX) or not shutil.which("systemd-analyze"):
    print("FAIL: needs tests/tools/sandbox-run (libseccomp-dev) and systemd-analyze")
    sys.exit(1)

settings = {}
with open(UNIT) as f:
    for line in f:
        line = line.strip()
        if line and not line.startswith("#") and "=" in line:
            key, _, value = line.partition("=")
            settings.setdefault(key, []).append(value)


def expand(group, seen):
    out = subprocess.run(["systemd-analyze", "syscall-filter", group], capture_output=True,
                         text=True).stdout
    names = set()
    for line in out.splitlines()[1:]:
        item = line.strip()
        if not item or item.startswith("#"):
            continue
        if item.startswith("@"):
            if item not in seen:
                seen.add(item)
                names |= expand(item, seen)
        else:
            names.add(item)
    return names


def syscall_allow_list():
    """SystemCallFilter= lines as systemd combines them: the first sets an
    allow-list, a later "~" line takes its groups out."""
    allowed = None
    for value in settings.get("SystemCallFilter", []):
        deny = value.startswith("~")
        names = set()
        for item in value.lstrip("~").split():
            names |= expand(item, set()) if item.startswith("@") else {item}
        if deny:
            allowed = (allowed if allowed is not None else set()) - names
        else:
            allowed = (allowed or set()) | names
    return allowed


tmp = tempfile.mkdtemp(prefix="shadebench-sandbox-")
allow_path = os.path.join(tmp, "allow.txt")
allowed = syscall_allow_list()
check(allowed is not None and len(allowed) > 100, "the unit sets a syscall allow-list")
with open(allow_path, "w") as f:
    f.write("\n".join(sorted(allowed or [])) + "\n")
# A small job for each option alone; the whole pipeline (OSL's compute
# pass, the reference, the metrics thread) under every option at once.
job_path = os.path.join(tmp, "job.json")
with open(job_path, "w") as f:
    f.write('{"frames": 2, "warmup_frames": 0, "scene": {"width": 64, "height": 48}}')
full_job_path = os.path.join(tmp, "full.json")
with open(full_job_path, "w") as f:
    f.write('{"technique": "osl", "frames": 4, "warmup_frames": 1, "capture_interval": 2, '
            '"osl": {"resolution": "auto"}, "reference": "forward", '
            '"scene": {"width": 96, "height": 64}}')

OPTIONS = []
if "SystemCallFilter" in settings:
    OPTIONS.append(("SystemCallFilter", ["--allow", allow_path]))
if "RestrictAddressFamilies" in settings:
    OPTIONS.append(("RestrictAddressFamilies",
                    ["--families", ",".join(settings["RestrictAddressFamilies"][-1].split())]))
if settings.get("RestrictRealtime") == ["yes"]:
    OPTIONS.append(("RestrictRealtime", ["--no-realtime"]))
if settings.get("RestrictNamespaces") == ["yes"]:
    OPTIONS.append(("RestrictNamespaces", ["--no-namespaces"]))
if settings.get("LockPersonality") == ["yes"]:
    OPTIONS.append(("LockPersonality", ["--lock-personality"]))
PROC = settings.get("ProcSubset") == ["pid"] or "ProtectProc" in settings


# LeakSanitizer stops the process with ptrace to scan it, which the syscall
# filter (rightly) forbids: in the sanitizer build the sandboxed runs check
# memory errors but not leaks (the rest of make check does).
ENV = dict(os.environ)
if ENV.get("SHADEBENCH_SANITIZERS"):
    ENV["ASAN_OPTIONS"] = ENV.get("ASAN_OPTIONS", "") + ":detect_leaks=0"


def in_private_proc(cmd):
    """ProtectProc=invisible and ProcSubset=pid: /proc without its system
    files and without other users' processes. The command keeps its pid (no
    pid namespace), so that SIGTERM reaches the daemon itself."""
    script = "mount -t proc -o hidepid=invisible,subset=pid proc /proc && exec \"$@\""
    return ["unshare", "--mount", "sh", "-c", script, "sh"] + cmd


def run_once(name, sandbox_args, private_proc=False, job=None):
    out_dir = os.path.join(tmp, "out-" + name)
    cmd = [SANDBOX] + sandbox_args + ["--", testlib.SHADEBENCHD, "--once", job or job_path,
                                      "--out", out_dir]
    if private_proc:
        cmd = in_private_proc(cmd)
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=600 * testlib.TIME_SCALE,
                         env=ENV)
    done = os.path.exists(os.path.join(out_dir, "result.json")) and res.returncode == 0
    if not done:
        sys.stdout.write(res.stderr[-1500:])
    return done, res.returncode


for name, args in OPTIONS:
    ok, rc = run_once(name, args)
    check(ok, "%s as the unit sets it: the job renders and is scored on llvmpipe (exit %d)" % (name, rc))
if PROC:
    ok, rc = run_once("proc", [], private_proc=True)
    check(ok, "ProtectProc=invisible, ProcSubset=pid: the job runs (exit %d)" % rc)
all_args = [a for _, args in OPTIONS for a in args]
ok, rc = run_once("all", all_args, private_proc=PROC, job=full_job_path)
check(ok, "every option at once: the job runs (exit %d)" % rc)

# The HTTP side under every option: serve, answer, run a job, stop on SIGTERM.
port_file = os.path.join(tmp, "port")
cmd = [SANDBOX] + all_args + ["--", testlib.SHADEBENCHD, "--listen", "127.0.0.1:0", "--port-file",
                              port_file, "--state-dir", os.path.join(tmp, "state")]
log = open(os.path.join(tmp, "daemon.log"), "w")
proc = subprocess.Popen(in_private_proc(cmd) if PROC else cmd, stdout=log, stderr=subprocess.STDOUT,
                        env=ENV)
try:
    deadline = time.time() + 60 * testlib.TIME_SCALE
    while not os.path.exists(port_file) and proc.poll() is None and time.time() < deadline:
        time.sleep(0.05)
    check(os.path.exists(port_file), "the sandboxed daemon listens")
    if os.path.exists(port_file):
        d = testlib.Daemon.__new__(testlib.Daemon)
        with open(port_file) as f:
            d.base = "http://127.0.0.1:%d" % int(f.read())
        check(d.json("GET", "/healthz")[0] == 200, "sandboxed: /healthz answers")
        job = d.run({"frames": 3, "warmup_frames": 0, "scene": {"width": 64, "height": 48}})
        check(job.get("status") == "done", "sandboxed: a job runs over HTTP: %s" % job.get("error"))
        check(d.json("GET", "/metrics")[0] == 200, "sandboxed: /metrics answers")
finally:
    if proc.poll() is None:
        proc.send_signal(15)
    try:
        proc.wait(30 * testlib.TIME_SCALE)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
    log.close()
check(proc.returncode == 0, "sandboxed: SIGTERM exits 0 (got %s)" % proc.returncode)

# MemoryDenyWriteExecute is left out of the unit because it breaks the JIT.
check(settings.get("MemoryDenyWriteExecute", ["no"])[-1] != "yes",
      "the unit leaves MemoryDenyWriteExecute out")
ok, rc = run_once("mdwe", ["--mdwe"])
check(not ok, "MemoryDenyWriteExecute breaks llvmpipe's shader JIT (exit %d), as the unit says" % rc)
if testlib.failures:
    with open(os.path.join(tmp, "daemon.log")) as f:
        sys.stdout.write(f.read()[-3000:])
shutil.rmtree(tmp, ignore_errors=True)
testlib.finish("systemd_sandbox")
