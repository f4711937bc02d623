#!/usr/bin/env python3
"""The folders are the layers (docs/architecture.md): a folder includes only
folders below it in LAYERS, never one beside or above it, and the client
only the GL-free layers it links (CLIENT_MAY), never the API, the harness,
the store or the jobs' threads. Reads every #include "..." of daemon/,
common/ and client/; fails naming each include that breaks the rule."""
import glob
import os
import re
import sys

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Top to bottom; folders in one row are beside each other.
LAYERS = [
    ["daemon/main", "client"],
    ["daemon/api"],
    ["daemon/harness"],
    ["daemon/reports"],
    ["daemon/status"],
    ["daemon/jobs"],
    ["daemon/store"],
    ["daemon/spec"],
    ["daemon/look"],
    ["daemon/techniques"],
    ["daemon/lighting"],
    ["daemon/effects"],
    ["daemon/gpu"],
    ["daemon/assets", "daemon/reference", "daemon/service"],
    ["daemon/quality", "daemon/scene"],
    ["common"],
]
CLIENT_MAY = {"common", "daemon/quality", "daemon/scene", "daemon/lighting", "daemon/effects",
              "daemon/techniques", "daemon/spec", "daemon/reports"}
RANK = {f: i for i, row in enumerate(LAYERS) for f in row}


def folder(path):
    parts = path.split("/")
    if parts[0] == "daemon":  # a folder, or a file of daemon/ itself (main, service)
        return "daemon/" + (parts[1] if len(parts) > 2 else os.path.splitext(parts[1])[0])
    return parts[0]


def main():
    os.chdir(TOP)
    files = sorted(glob.glob("daemon/**/*.[ch]", recursive=True) + glob.glob("common/*.[ch]") +
                   glob.glob("client/*.[ch]"))
    bad, seen = [], 0
    for path in files:
        f = folder(path)
        if f not in RANK:
            bad.append("%s: its folder %s has no layer in tests/layers.py" % (path, f))
            continue
        with open(path, encoding="utf-8") as src:
            for n, line in enumerate(src, 1):
                m = re.match(r'\s*#\s*include\s+"((?:daemon|common|client)/[^"]+)"', line)
                if not m:
                    continue
                g = folder(m.group(1))
                seen += 1
                if g == f:
                    continue
                if g not in RANK:
                    bad.append("%s:%d: %s is in no layer" % (path, n, m.group(1)))
                elif f == "client" and g not in CLIENT_MAY:
                    bad.append("%s:%d: the client includes %s (it links only %s)"
                               % (path, n, m.group(1), ", ".join(sorted(CLIENT_MAY))))
                elif RANK[g] <= RANK[f]:
                    bad.append("%s:%d: %s (%s) includes %s, which is %s it"
                               % (path, n, f, "layer %d" % RANK[f], m.group(1),
                                  "beside" if RANK[g] == RANK[f] else "above"))
    for b in bad:
        print("FAIL: " + b)
    print("layers: %d files, %d includes of ours, %d break the layers" % (len(files), seen, len(bad)))
    return 1 if bad or not seen else 0


if __name__ == "__main__":
    sys.exit(main())
