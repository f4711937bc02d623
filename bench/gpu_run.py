#!/usr/bin/env python3
"""Issue 38's GPU run, prepared for whoever gets a machine with a GPU: the
devices and their names, the suite's GL tests that make sense there, and
the benchmark tables of docs/benchmarks.md in a short run, all within a
time budget (default 450 s), written under $OUT (or --out).

Here, after a build (root, Debian's packages; once):

    bench/gpu_run.py --prepare

packs the built programs, their libraries and the GL loaders into .gpu/
(/work/shared/tools/gpu-bundle, or $GPU_BUNDLE) and adds the tests' PNG
tool. Carry `.gpu` to the GPU machine; there, from the repository root:

    bench/gpu_run.py [--budget 450] [--device auto] [--out DIR]

It unpacks the loaders where the machine has no libEGL (`. .gpu/enter`),
runs the bundle's programs (else build/'s), and writes at most eight files
(what the device tool brings back):

    summary.txt    each step: what ran, its exit status and time; the device
    devices.txt    nvidia-smi, NVIDIA's procfs, /dev and /sys, and
                   shadebenchd --list-devices
    devices.json   shadebenchd --list-devices --json
    tests.log      each test's output
    bench.log      each benchmark's output (its tables, the commit, the
                   command and the load, as bench/benchrun.py prints them)
    results.tar.gz the benchmarks' --json files and charts

--quick runs tiny settings (e2e_gpu alone, small frames): a check that the
script runs end to end, on llvmpipe too; its figures mean nothing.
Standard library only (the GPU machine's python3 has no more than that
for sure)."""

import argparse
import datetime
import json
import os
import shlex
import shutil
import signal
import subprocess
import sys
import tarfile
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
BUNDLE = os.path.join(ROOT, ".gpu")

# The GL tests that say something on a GPU: device names and costs, every
# technique against forward with every pass timed, MSAA, the post effects,
# physically based lighting, light types, many lights, textures, OSL, the
# runaway guard and measurement integrity. Left out: HTTP, the store, the
# fleet and the converter (not the GPU's), and Chromium's reference.
TESTS = ["e2e_gpu", "e2e_techniques", "e2e_msaa", "e2e_post", "e2e_pbr", "e2e_light_types",
         "e2e_many_lights", "e2e_textured", "e2e_osl", "e2e_runaway", "e2e_integrity", "e2e_scene"]

# The tables of docs/benchmarks.md (and the pages it points to) at their
# documented sizes, with fewer frames and repeats; each (name, budget share,
# arguments, quick arguments). {asset} is the generated realistic asset.
BENCHES = [
    ("thesis", 0.20, ["bench/bench.py", "--frames", "30", "--warmup", "5", "--repeat", "2"],
     ["bench/bench.py", "--frames", "2", "--warmup", "1", "--repeat", "1", "--width", "96",
      "--height", "64", "--only", "forward,unlit"]),
    ("lights", 0.22, ["bench/bench_lights_techniques.py", "--frames", "10", "--frames-high", "5",
                      "--warmup", "2", "--repeat", "1", "--forward-max", "4096", "--svg", "{dir}/lights.svg"],
     ["bench/bench_lights_techniques.py", "--counts", "16,64", "--techniques", "unlit,forward,deferred",
      "--frames", "2", "--warmup", "1", "--repeat", "1", "--width", "96", "--height", "64",
      "--svg", "{dir}/lights.svg"]),
    ("msaa", 0.18, ["bench/bench_msaa.py", "--counts", "16,1024", "--frames", "10", "--warmup", "2",
                    "--repeat", "1"],
     ["bench/bench_msaa.py", "--counts", "16", "--levels", "1,2", "--techniques", "forward,deferred",
      "--frames", "2", "--warmup", "1", "--repeat", "1", "--width", "96", "--height", "64"]),
    ("osl", 0.16, ["bench/bench_osl.py", "--frames", "20", "--warmup", "3", "--repeat", "2",
                   "--distances", "1,20"],
     ["bench/bench_osl.py", "--frames", "2", "--warmup", "1", "--repeat", "1", "--distances", "20",
      "--width", "96", "--height", "64"]),
    ("post", 0.12, ["bench/bench_post.py", "--frames", "20", "--repeat", "2", "--only",
                    "bloom,ssao,chain"],
     ["bench/bench_post.py", "--frames", "2", "--warmup", "1", "--repeat", "1", "--only", "bloom",
      "--width", "96", "--height", "64"]),
    ("asset", 0.12, ["bench/bench_lights_techniques.py", "--asset", "{asset}", "--counts",
                     "16,256,1024,4096", "--frames", "10", "--frames-high", "5", "--warmup", "2",
                     "--repeat", "1", "--width", "540", "--height", "360", "--forward-max", "4096",
                     "--svg", "{dir}/lights-asset.svg"],
     ["bench/bench_lights_techniques.py", "--asset", "{asset}", "--counts", "16,64", "--techniques",
      "unlit,forward", "--frames", "2", "--warmup", "1", "--repeat", "1", "--width", "96",
      "--height", "64", "--svg", "{dir}/lights-asset.svg"]),
]


def sh(cmd, **kw):
    return subprocess.run(cmd, shell=isinstance(cmd, str), capture_output=True, text=True, **kw)


def prepare(args):
    """Here: the bundle, with the tests' PNG tool added."""
    build = os.path.join(ROOT, "build")
    r = subprocess.run(["make", "-C", build, "tests/tools/png-tool"], text=True)
    if r.returncode != 0:
        sys.exit("gpu_run: building tests/tools/png-tool failed (tools/setup first)")
    tool = os.environ.get("GPU_BUNDLE", "/work/shared/tools/gpu-bundle")
    if subprocess.run([tool], cwd=ROOT).returncode != 0:
        sys.exit("gpu_run: %s failed" % tool)
    png = os.path.join(build, "tests", "tools", "png-tool")
    shutil.copy(png, os.path.join(BUNDLE, "bin", "png-tool"))
    for line in sh(["ldd", png]).stdout.splitlines():
        parts = line.split()
        lib = parts[2] if len(parts) > 2 and parts[1] == "=>" else ""
        base = os.path.basename(lib)
        if (lib.startswith("/") and not os.path.exists(os.path.join(BUNDLE, "lib", base)) and
                not base.startswith(("libc.", "libm.", "ld-linux", "libstdc++", "libgcc_s"))):
            shutil.copy(lib, os.path.join(BUNDLE, "lib", base))
    size = sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(BUNDLE) for f in fs)
    print("gpu_run: .gpu/ ready (%.0f MB); on the GPU machine, from the repository root: "
          "bench/gpu_run.py (carry .gpu)" % (size / 1e6))


def environment():
    """The variables the run needs: the bundle's programs and libraries, the
    GL loaders unpacked where the machine has none, NVIDIA's EGL vendor file."""
    env = dict(os.environ)
    if os.path.exists(os.path.join(BUNDLE, "enter")):
        has_egl = "libEGL.so.1" in sh(["sh", "-c", "ldconfig -p 2>/dev/null"]).stdout
        if not has_egl:
            r = sh(["sh", "-c", ". .gpu/enter >/dev/null 2>&1; env -0"], cwd=ROOT)
            env = dict(kv.split("=", 1) for kv in r.stdout.split("\0") if "=" in kv)
        else:
            env["LD_LIBRARY_PATH"] = os.path.join(BUNDLE, "lib") + (
                ":" + env["LD_LIBRARY_PATH"] if env.get("LD_LIBRARY_PATH") else "")
            env["PATH"] = os.path.join(BUNDLE, "bin") + ":" + env.get("PATH", "")
        nvidia = "/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json"
        if os.path.exists(nvidia) and "__EGL_VENDOR_LIBRARY_FILENAMES" not in env:
            env["__EGL_VENDOR_LIBRARY_FILENAMES"] = nvidia
        bindir = os.path.join(BUNDLE, "bin")
    else:
        bindir = os.path.join(ROOT, "build")
    progs = {"SHADEBENCHD": "shadebenchd", "SHADEBENCH_CLIENT": "shadebench",
             "SHADEBENCH_COMPARE": "shadebench-compare"}
    for var, name in progs.items():
        env[var] = os.path.join(bindir, name)
    env["PNG_TOOL"] = (os.path.join(bindir, "png-tool") if bindir.startswith(BUNDLE)
                       else os.path.join(ROOT, "build", "tests", "tools", "png-tool"))
    env["PYTHONUNBUFFERED"] = "1"
    return env


class Budget:
    def __init__(self, seconds):
        self.end = time.monotonic() + seconds

    def left(self):
        return self.end - time.monotonic()


def step(cmd, env, timeout, log, cwd=ROOT):
    """Runs cmd with its output appended to log; (exit status or 'timed
    out', seconds). On time, its whole process group goes (the daemons a
    test or bench started with it)."""
    t0 = time.monotonic()
    log.write("\n$ %s\n" % " ".join(shlex.quote(c) for c in cmd))
    log.flush()
    proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=log, stderr=subprocess.STDOUT,
                            start_new_session=True)
    try:
        status = proc.wait(timeout=max(1, timeout))
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        status = "timed out after %.0f s" % timeout
    log.write("\n[%s, %.0f s]\n" % (status, time.monotonic() - t0))
    log.flush()
    return status, time.monotonic() - t0


def devices(env, out, summary):
    with open(os.path.join(out, "devices.txt"), "w") as f:
        for title, cmd in (
                ("nvidia-smi", "nvidia-smi --query-gpu=index,name,pci.bus_id,uuid,driver_version,"
                               "memory.total --format=csv 2>&1 || echo 'no nvidia-smi'"),
                ("NVIDIA's procfs", "cat /proc/driver/nvidia/gpus/*/information 2>&1"),
                ("device files", "ls -l /dev/dri /dev/nvidia* 2>&1; ls -l /sys/class/drm 2>&1"),
                ("ROCm's topology", "ls /sys/class/kfd/kfd/topology/nodes 2>&1"),
                ("EGL vendor files", "ls /usr/share/glvnd/egl_vendor.d "
                                     "/usr/local/nvidia/share/glvnd/egl_vendor.d 2>&1; "
                                     "echo __EGL_VENDOR_LIBRARY_FILENAMES=$__EGL_VENDOR_LIBRARY_FILENAMES"),
                ("scheduler", "env | grep -E '^(SLURM_.*GPUS|CUDA_VISIBLE_DEVICES|"
                              "ROCR_VISIBLE_DEVICES|GPU_DEVICE_ORDINAL)=' || echo none"),
                ("shadebenchd --list-devices", shlex.quote(env["SHADEBENCHD"]) + " --list-devices 2>&1")):
            f.write("== %s\n%s\n" % (title, sh(cmd, env=env, timeout=60).stdout))
    r = sh([env["SHADEBENCHD"], "--list-devices", "--json"], env=env, timeout=60)
    with open(os.path.join(out, "devices.json"), "w") as f:
        f.write(r.stdout or json.dumps({"error": r.stderr}))
    try:
        listed = json.loads(r.stdout)["devices"]
    except (ValueError, KeyError):
        listed = []
    hardware = [d for d in listed if d.get("opens") and not d.get("software")]
    summary.append("devices: %d EGL device(s), %d hardware that opens: %s" % (
        len(listed), len(hardware), "; ".join("%d %s (%s, bus %s)" % (
            d["index"], d.get("renderer"), d.get("gl_version"), d.get("bus_id")) for d in listed)))
    if not hardware:
        summary.append("WARNING: no hardware EGL device opens: what follows runs on a software "
                       "renderer (see devices.txt)")


def run_tests(env, out, budget, quick, summary):
    names = ["e2e_gpu"] if quick else TESTS
    work = tempfile.mkdtemp(prefix="gpu-run-tests-")
    with open(os.path.join(out, "tests.log"), "w") as log:
        for name in names:
            left = budget.left()
            if left < 10:
                summary.append("test %s: not run, out of time" % name)
                continue
            status, secs = step([sys.executable, os.path.join(ROOT, "tests", "e2e", name + ".py")],
                                env, min(left, 150), log, cwd=work)
            summary.append("test %s: %s, %.0f s" % (name, "passed" if status == 0 else
                                                    "FAILED (%s)" % status, secs))
    shutil.rmtree(work, ignore_errors=True)


def run_benches(env, out, budget, quick, summary):
    work = tempfile.mkdtemp(prefix="gpu-run-bench-")
    asset = os.path.join(work, "realistic.glb")
    sys.path.insert(0, os.path.join(ROOT, "tests", "e2e"))
    import gltf_gen  # noqa: E402
    with open(asset, "wb") as f:
        f.write(gltf_gen.realistic_asset().glb())
    total = budget.left()
    with open(os.path.join(out, "bench.log"), "w") as log:
        for name, share, full, small in BENCHES:
            left = budget.left()
            if left < 15:
                summary.append("bench %s: not run, out of time" % name)
                continue
            cmd = [a.format(dir=work, asset=asset) for a in (small if quick else full)]
            cmd = [sys.executable, os.path.join(ROOT, cmd[0])] + cmd[1:] + [
                "--json", os.path.join(work, name + ".json")]
            # A share of the whole, or more when earlier steps ended early;
            # --quick's tiny runs take what is left (on a CPU renderer the
            # thesis grid's geometry, not the size, sets their time).
            limit = left if quick else min(left, max(share * total, left * share * 2))
            status, secs = step(cmd, env, limit, log)
            summary.append("bench %s: %s, %.0f s" % (name, "done" if status == 0 else
                                                     "FAILED (%s)" % status, secs))
    with tarfile.open(os.path.join(out, "results.tar.gz"), "w:gz") as tar:
        for f in sorted(os.listdir(work)):
            if f.endswith((".json", ".svg")):
                tar.add(os.path.join(work, f), arcname=f)
    shutil.rmtree(work, ignore_errors=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--prepare", action="store_true", help="here: pack .gpu/ for the GPU machine")
    ap.add_argument("--quick", action="store_true", help="tiny settings: the script's own check")
    ap.add_argument("--budget", type=float, default=450, help="seconds for the whole run")
    ap.add_argument("--tests-share", type=float, default=0.35, help="the tests' share of the budget")
    ap.add_argument("--device", default="auto", help="shadebenchd --device for every step")
    ap.add_argument("--out", default=os.environ.get("OUT") or "",
                    help="where the files go (default $OUT, else gpu-run-DATE)")
    ap.add_argument("--skip-tests", action="store_true")
    ap.add_argument("--skip-bench", action="store_true")
    args = ap.parse_args()
    if args.prepare:
        prepare(args)
        return 0
    out = args.out or os.path.join(ROOT, "gpu-run-" + time.strftime("%Y%m%d-%H%M%S"))
    os.makedirs(out, exist_ok=True)
    budget = Budget(args.budget)
    env = environment()
    env["SHADEBENCH_DEVICE"] = args.device  # every daemon the tests and benches start
    commit = sh(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"]).stdout.strip() or "unknown"
    summary = ["gpu_run: %s, commit %s, %d CPUs, %s" % (
        datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"), commit,
        os.cpu_count(), "quick (figures mean nothing)" if args.quick else "budget %.0f s" % args.budget),
        "shadebenchd: %s, --device %s" % (env["SHADEBENCHD"], args.device)]
    if not os.access(env["SHADEBENCHD"], os.X_OK):
        summary.append("no %s: run bench/gpu_run.py --prepare here first" % env["SHADEBENCHD"])
    else:
        devices(env, out, summary)
        if not args.skip_tests:
            run_tests(env, out, Budget(min(budget.left(), args.budget * args.tests_share)),
                      args.quick, summary)
        if not args.skip_bench:
            run_benches(env, out, budget, args.quick, summary)
    summary.append("ended after %.0f s" % (args.budget - budget.left()))
    with open(os.path.join(out, "summary.txt"), "w") as f:
        f.write("\n".join(summary) + "\n")
    print("\n".join(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
