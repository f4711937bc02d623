"""A one-node Slurm cluster on this machine, for the fleet tests: munged with
a fresh key on its own socket, slurmctld and slurmd from Debian's packages
(slurm-wlm, munge; tools/setup installs them) with a slurm.conf written here:
one node, one partition, two generic "gpu" resources (File=/dev/null and
/dev/zero stand in for device files) and two node features standing for two
device classes. No accounting database: sacct answers nothing, and the
client reads task states from scontrol (MinJobAge keeps finished jobs in
slurmctld for an hour). Needs root (slurmd runs jobs as their user).
Standard library only."""

import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time

FEATURES = ("dev_a", "dev_b")
PARTITION = "sbtest"


def missing_requirements():
    """Why a cluster cannot start here, or None."""
    for exe in ("munged", "slurmctld", "slurmd", "sbatch", "squeue", "scontrol", "scancel"):
        if not shutil.which(exe) and not os.path.exists("/usr/sbin/" + exe):
            return "%s is not installed (tools/setup installs slurm-wlm and munge)" % exe
    if os.geteuid() != 0:
        return "slurmd must run as root (CI runs the suite as root)"
    return None


def _free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def _sbin(exe):
    return shutil.which(exe) or "/usr/sbin/" + exe


class Cluster:
    def __init__(self, extra_conf=""):
        self.dir = tempfile.mkdtemp(prefix="shadebench-slurm-")
        d = self.dir
        for sub in ("state", "spool", "log", "munge"):
            os.makedirs(os.path.join(d, sub))
        os.chmod(os.path.join(d, "munge"), 0o700)
        key = os.path.join(d, "munge", "munge.key")
        with open(key, "wb") as f:
            f.write(os.urandom(1024))
        os.chmod(key, 0o400)
        self.sock = os.path.join(d, "munge", "munge.socket")
        self.host = socket.gethostname().split(".")[0]
        self.conf = os.path.join(d, "slurm.conf")
        self.env = dict(os.environ, SLURM_CONF=self.conf)
        self.pids = []
        subprocess.run([_sbin("munged"), "--key-file", key, "--socket", self.sock,
                        "--pid-file", os.path.join(d, "munge", "munged.pid"),
                        "--log-file", os.path.join(d, "log", "munged.log"),
                        "--seed-file", os.path.join(d, "munge", "seed"), "--force"],
                       check=True)
        self.pid_files = [os.path.join(d, "munge", "munged.pid")]
        with open(self.conf, "w") as f:
            f.write(f"""ClusterName=sbtest
SlurmctldHost={self.host}(127.0.0.1)
SlurmctldPort={_free_port()}
SlurmdPort={_free_port()}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={self.sock}
StateSaveLocation={d}/state
SlurmdSpoolDir={d}/spool
SlurmctldPidFile={d}/slurmctld.pid
SlurmdPidFile={d}/slurmd.pid
SlurmctldLogFile={d}/log/slurmctld.log
SlurmdLogFile={d}/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/builtin
# Start batch jobs as soon as resources free up, not up to 3 s later (the
# default, for clusters that take thousands of submissions a second): the
# fleet's array tasks are short here.
SchedulerParameters=batch_sched_delay=0
MpiDefault=none
ReturnToService=2
GresTypes=gpu
MinJobAge=3600
SlurmdTimeout=30
InactiveLimit=0
KillWait=2
NodeName={self.host} NodeAddr=127.0.0.1 CPUs={os.cpu_count() or 2} RealMemory=1000 Gres=gpu:2 Feature={",".join(FEATURES)} State=UNKNOWN
PartitionName={PARTITION} Nodes={self.host} Default=YES MaxTime=INFINITE State=UP OverSubscribe=YES
{extra_conf}""")
        with open(os.path.join(d, "gres.conf"), "w") as f:
            f.write(f"NodeName={self.host} Name=gpu File=/dev/null\n"
                    f"NodeName={self.host} Name=gpu File=/dev/zero\n")
        # slurmd reads cgroup.conf beside slurm.conf when present; an empty
        # one keeps it from the system's.
        open(os.path.join(d, "cgroup.conf"), "w").close()
        self.pid_files += [os.path.join(d, "slurmctld.pid"), os.path.join(d, "slurmd.pid")]
        subprocess.run([_sbin("slurmctld"), "-f", self.conf, "-i"], env=self.env, check=True)
        subprocess.run([_sbin("slurmd"), "-f", self.conf, "-N", self.host], env=self.env,
                       check=True)
        deadline = time.time() + 60
        while True:
            r = subprocess.run(["sinfo", "-h", "-o", "%T"], env=self.env, capture_output=True,
                               text=True)
            if r.stdout.strip() == "idle":
                break
            if time.time() > deadline:
                self.dump_logs()
                self.stop()
                raise RuntimeError("the Slurm node did not come up: %s %s"
                                   % (r.stdout, r.stderr))
            time.sleep(0.2)

    def run(self, *args, **kw):
        return subprocess.run(list(args), env=self.env, capture_output=True, text=True, **kw)

    def squeue(self, job):
        """[(array task id, state)] of an array's tasks still in the queue."""
        r = self.run("squeue", "-h", "-r", "-j", str(job), "-o", "%K %T")
        out = []
        for line in r.stdout.splitlines():
            parts = line.split()
            if len(parts) == 2:
                out.append((parts[0], parts[1]))
        return out

    def dump_logs(self):
        for name in ("slurmctld.log", "slurmd.log"):
            try:
                with open(os.path.join(self.dir, "log", name)) as f:
                    print("--- %s (tail)\n%s" % (name, f.read()[-3000:]))
            except OSError:
                pass

    def stop(self):
        """Stops every daemon this cluster started, whatever state it is in."""
        subprocess.run(["scancel", "--partition", PARTITION], env=self.env, capture_output=True)
        # All three at once: each takes about 2 s to end on SIGTERM (5.6 s
        # one after another, 1.9 s together).
        pids = []
        for pf in reversed(self.pid_files):
            try:
                with open(pf) as f:
                    pid = int(f.read().strip())
                os.kill(pid, signal.SIGTERM)
                pids.append(pid)
            except (OSError, ValueError):
                pass
        deadline = time.time() + 5
        for pid in pids:
            try:
                while time.time() < deadline:
                    os.kill(pid, 0)
                    time.sleep(0.05)
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        shutil.rmtree(self.dir, ignore_errors=True)
