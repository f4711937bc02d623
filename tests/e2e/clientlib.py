"""Running the shadebench client against a test daemon: the client binary,
job files in the daemon's temporary folder, JUnit parsing."""

import json
import os
import subprocess
import xml.etree.ElementTree as ET

CLIENT = os.environ.get("SHADEBENCH_CLIENT", "./shadebench")


class Client:
    def __init__(self, daemon, token=None):
        self.d = daemon
        self.token = token

    def run(self, *args, env_token=True, extra_env=None, timeout=900):
        env = dict(os.environ, SHADEBENCH_SERVER=self.d.base)
        # The tests choose these themselves: a CI shell's own settings
        # (SHADEBENCH_FAIL_INCONCLUSIVE=1, say) must not change them.
        for k in ("SHADEBENCH_TOKEN", "SHADEBENCH_TOKEN_FILE", "SHADEBENCH_FAIL_INCONCLUSIVE"):
            env.pop(k, None)
        if env_token and self.token:
            env["SHADEBENCH_TOKEN"] = self.token
        env.update(extra_env or {})
        return subprocess.run([CLIENT] + [str(a) for a in args], capture_output=True, text=True,
                              env=env, timeout=timeout)

    def write(self, name, obj):
        path = os.path.join(self.d.tmp, name + ".json")
        with open(path, "w") as f:
            json.dump(obj, f)
        return path

    def path(self, *parts):
        return os.path.join(self.d.tmp, *parts)


def junit_cases(path):
    """{name: (failure message or None, time, {property: value}, system-out)}"""
    root = ET.parse(path).getroot()
    cases = {}
    for c in root.iter("testcase"):
        fail = c.find("failure")
        props = {p.get("name"): p.get("value") for p in c.iter("property")}
        out = c.find("system-out")
        cases[c.get("name")] = (fail.get("message") if fail is not None else None,
                                float(c.get("time")), props, out.text if out is not None else "")
    return root, cases
