"""The GPU as a lab names it, and the costs a GPU user asks for (issue 38),
on the machine at hand (llvmpipe in CI; bench/gpu_run.py runs it on a GPU):
--list-devices (text and JSON); --device by every name the first device
has (the index alone on llvmpipe; a GPU's node, bus id and UUID too), and by
a node, a PCI bus id, a UUID or an index that match nothing (a clear
start-up error listing the devices); /v1/info's devices and selection; --device
allocated under Slurm's variables on a box without GPUs (the default choice,
with the reason) and with a fake NVIDIA driver (the GPU it names, which EGL
lacks: an error); compile time per program in every result, outside the
timed region, programs seen before on a second job; GPU memory where the
driver reports it, else absent with the reason, beside the target pool's
bytes."""

import json
import os
import shutil
import subprocess
import tempfile

import testlib
from testlib import check

testlib.skip_without_egl()
S = testlib.TIME_SCALE
D = testlib.SHADEBENCHD
JOB = {"technique": "forward", "frames": 3, "warmup_frames": 1,
       "scene": {"width": 48, "height": 32}}
tmp = tempfile.mkdtemp(prefix="shadebench-gpu-")


def run(*args, env=None, timeout=120):
    full = dict(os.environ)
    full.update(env or {})
    return subprocess.run([D] + list(args), capture_output=True, text=True, env=full,
                          timeout=timeout * S)


def once(name, *args, env=None):
    job = os.path.join(tmp, "job.json")
    with open(job, "w") as f:
        json.dump(JOB, f)
    out = os.path.join(tmp, name)
    return run("--once", job, "--out", out, *args, env=env), out


def load(path):
    with open(path) as f:
        return json.load(f)


# --list-devices: each device with its names (llvmpipe here; a GPU box's
# devices there: bench/gpu_run.py runs this test on one).
r = run("--list-devices", "--json")
devs = json.loads(r.stdout)["devices"] if r.returncode == 0 else []
check(len(devs) >= 1 and [x["index"] for x in devs] == list(range(len(devs))),
      "--list-devices --json lists the EGL devices: %s" % devs)
opened = [x for x in devs if x.get("opens")]
check(len(opened) >= 1 and all(x["gl_version"].startswith(("4.", "5.")) and x["renderer"]
                                for x in opened), "a device opens with its renderer: %s" % devs)
dev0 = opened[0] if opened else {"index": 0, "software": True}
SOFTWARE = dev0.get("software", True)
if SOFTWARE:
    check("llvmpipe" in dev0.get("renderer", "") and
          all(dev0.get(k, "x") is None for k in ("drm_node", "render_node", "bus_id", "uuid")),
          "llvmpipe has a name but no node, bus id or UUID: %s" % dev0)
r = run("--list-devices")
check(r.returncode == 0 and ("%d: %s" % (dev0["index"], dev0.get("renderer"))) in r.stdout and
      ("--device     %d" % dev0["index"]) in r.stdout,
      "--list-devices names each device and how to pick it: %s" % r.stdout)
for label, key in (("DRM node", "render_node"), ("PCI bus id", "bus_id"), ("UUID", "uuid")):
    check(("    %-12s %s" % (label, dev0.get(key) or "-")) in r.stdout,
          "--list-devices shows the %s: %s" % (label, r.stdout))
check(run("--json").returncode == 2, "--json alone is refused")

# A name that matches nothing: the daemon does not start, and says what exists.
for name, what in (("/dev/dri/renderD250", "the device node /dev/dri/renderD250"),
                   ("00ff:fe:1f.7", "the PCI bus id 00ff:fe:1f.7"),
                   ("GPU-ffffffff-ffff-ffff-ffff-fffffffffffe",
                    "the UUID ffffffff-ffff-ffff-ffff-fffffffffffe"),
                   (str(len(devs) + 3), "the index %d" % (len(devs) + 3))):
    r = run("--device", name, "--listen", "127.0.0.1:0", "--state-dir", os.path.join(tmp, "st"))
    check(r.returncode == 1 and ("no EGL device has %s" % what) in r.stderr and
          ("%d EGL device(s): 0: " % len(devs)) in r.stderr and
          ("%d: %s" % (dev0["index"], dev0.get("renderer"))) in r.stderr,
          "--device %s fails at start naming the devices: %d %s" % (name, r.returncode, r.stderr))
if SOFTWARE:
    r = run("--device", "/dev/dri/renderD128", "--listen", "127.0.0.1:0")
    check("0: llvmpipe" in r.stderr and "[software], node -, bus id -, uuid -" in r.stderr,
          "llvmpipe is listed with no node, bus id or UUID: %s" % r.stderr)
r = run("--device", "llvmpipe", "--list-devices")
check(r.returncode == 2 and '"llvmpipe" names no device' in r.stderr and "allocated" in r.stderr,
      "a --device that is no name at all is refused with the forms: %s" % r.stderr)

# Every name the first device that opens has picks it (the index alone on
# llvmpipe; a GPU's node, bus id, UUID and /dev/nvidiaN too).
names = [(str(dev0["index"]), "index")]
for key, kind in (("render_node", "node"), ("drm_node", "node"), ("bus_id", "bus_id")):
    if dev0.get(key):
        names.append((dev0[key], kind))
if dev0.get("uuid"):
    names.append(("GPU-" + dev0["uuid"], "uuid"))
if dev0.get("nvidia_minor") is not None:
    names.append(("/dev/nvidia%d" % dev0["nvidia_minor"], "node"))
for k, (name, kind) in enumerate(names):
    r, out = once("by-%d" % k, "--device", name)
    sel = load(os.path.join(out, "result.json"))["device"] if r.returncode == 0 else {}
    check(sel.get("egl_device_index") == dev0["index"] and
          sel.get("selection", {}).get("matched_by") == kind and
          sel["selection"]["asked"] == name,
          "--device %s opens device %d: %d %s %s" % (name, dev0["index"], r.returncode,
                                                     sel.get("selection"), r.stderr[-300:]))

# By index: /v1/info lists the devices and says which was opened and why.
d = testlib.Daemon("--device", str(dev0["index"]))
try:
    status, info = d.json("GET", "/v1/info")
    dev = info.get("device", {})
    sel = dev.get("selection", {})
    i = dev0["index"]
    check(sel.get("asked") == str(i) and sel.get("matched_by") == "index" and
          ("EGL device %d" % i) in sel.get("why", ""), "device.selection: %s" % sel)
    listed = dev.get("egl_devices", [])
    check(dev.get("egl_device_index") == i and dev.get("software") == SOFTWARE and
          dev.get("bus_id") == dev0.get("bus_id") and len(listed) == len(devs) and
          [x["selected"] for x in listed] == [x["index"] == i for x in devs] and
          listed[i]["renderer"] == dev0["renderer"], "device names: %s" % dev)
    mem = dev.get("gpu_memory_at_start", {})
    if mem.get("source"):
        check(mem["source"] in ("GL_NVX_gpu_memory_info", "GL_ATI_meminfo") and
              mem.get("available_kib", 0) > 0, "memory at start where the driver reports it: %s" % mem)
    else:
        check("source" in mem and "GL_NVX_gpu_memory_info" in mem.get("reason", ""),
              "memory at start absent with a reason: %s" % mem)

    # Compile time in the result, outside the timed region.
    first = d.run(JOB)
    res = first.get("result", {})
    comp = res.get("compile", {})
    progs = comp.get("programs", [])
    check(first.get("status") == "done" and comp.get("count", 0) >= 2 and len(progs) == comp["count"],
          "the result lists the programs built: %s" % {k: v for k, v in comp.items() if k != "method"})
    check(all(p["compile_ms"] >= 0 and p["link_ms"] >= 0 and p["stages"] >= 1 and
              abs(p["total_ms"] - p["compile_ms"] - p["link_ms"]) < 1e-6 for p in progs) and
          comp.get("total_ms", 0) > 0 and
          abs(comp["total_ms"] - sum(p["total_ms"] for p in progs)) < 1e-3,
          "each program's compile and link time, and their sum: %s" % progs)
    check(any(p["label"] == "forward" for p in progs), "forward's own program is listed: %s" %
          [p["label"] for p in progs])
    check(comp.get("in_timed_region") == 0, "no program built in the timed region: %s" %
          comp.get("in_timed_region"))
    cache = comp.get("cache", {})
    check(cache.get("driver") in ("mesa", "nvidia") and cache.get("disk_cache") in ("on", "off") and
          ("mesa_shader_cache" in cache.get("dir", "") or "GLCache" in cache.get("dir", "") or
           cache["driver"] == "nvidia") and "dir_exists" in cache,
          "the driver's shader cache is stated: %s" % cache)
    gm = res.get("gpu_memory", {})
    check(gm.get("pool_bytes") == res.get("targets_bytes") and res.get("targets_bytes", 0) > 0,
          "the pool's own bytes beside the driver's figures: %s" % gm)
    if gm.get("source"):
        av = gm.get("available_kib", {})
        check(all(isinstance(av.get(k), int) and av[k] > 0 for k in
                  ("before_setup", "after_setup", "after_frames")) and
              gm.get("setup_kib") == av["before_setup"] - av["after_setup"],
              "GPU memory where the driver reports it: %s" % gm)
    else:
        check("source" in gm and "neither" in gm.get("reason", "") and
              ("software" in gm["reason"]) == SOFTWARE,
              "GPU memory absent with a reason: %s" % gm)
    # The same job again: every program is one this process built before.
    again = d.run(dict(JOB, repeat=2)).get("result", {})
    comp2 = again.get("compile", {})
    check(comp2.get("count") == comp["count"] and comp2.get("seen_before") == comp2.get("count") and
          all(p["seen_before"] for p in comp2.get("programs", [])),
          "a second job's programs were seen before: %s of %s" % (comp2.get("seen_before"),
                                                                comp2.get("count")))
    runs = again.get("runs", [])
    check(len(runs) == 2 and all(isinstance(x.get("compile_ms"), float) for x in runs),
          "each run of a repeated job has its compile time: %s" % [x.get("compile_ms") for x in runs])
    check(d.stop() == 0, "the daemon stops cleanly")
finally:
    d.cleanup()

# --device allocated, as a fleet task: Slurm's gres on a box without GPUs
# (the test cluster's File=/dev/null) leaves the default choice, saying why.
empty = os.path.join(tmp, "empty-root")
os.makedirs(empty)
slurm_env = {"SLURM_JOB_GPUS": "0", "CUDA_VISIBLE_DEVICES": "0", "SHADEBENCH_SYSFS_ROOT": empty}
r, out = once("alloc", "--device", "allocated", env=slurm_env)
check(r.returncode == 0, "--device allocated without GPUs runs the job: %s" % r.stderr[-500:])
if r.returncode == 0:
    sel = load(os.path.join(out, "result.json"))["device"]["selection"]
    check(sel["asked"] == "allocated" and sel["matched_by"] == "auto" and
          "SLURM_JOB_GPUS=0 names GPU 0, but the node has no GPU device" in sel["why"],
          "the result says why it took the default device: %s" % sel)
    task = load(os.path.join(out, "task.json"))
    check(task.get("slurm", {}).get("gpus") == "0" and
          task["slurm"].get("cuda_visible_devices") == "0",
          "task.json keeps the scheduler's GPU variables: %s" % task.get("slurm"))
# A box whose NVIDIA driver has GPU 0 at 0000:41:00.0, which no EGL device
# here is: the task fails at start, naming the GPU and the devices.
nv = os.path.join(tmp, "nvidia-root", "proc", "driver", "nvidia", "gpus", "0000:41:00.0")
os.makedirs(nv)
with open(os.path.join(nv, "information"), "w") as f:
    f.write("Model: \t\t NVIDIA H100\nGPU UUID: \t GPU-8c5f3b1e-5d2a-4c6f-9b7e-1a2b3c4d5e6f\n"
            "Device Minor: \t 0\n")
r, out = once("alloc-nv", "--device", "allocated",
              env=dict(slurm_env, SHADEBENCH_SYSFS_ROOT=os.path.join(tmp, "nvidia-root")))
check(r.returncode == 1 and "--device allocated: no EGL device has the device node /dev/nvidia0"
      in r.stderr and "EGL device(s): 0: " in r.stderr and not os.path.exists(out),
      "Slurm's GPU that EGL does not have fails the task clearly: %d %s" % (r.returncode, r.stderr))

shutil.rmtree(tmp, ignore_errors=True)
testlib.finish("e2e_gpu")
