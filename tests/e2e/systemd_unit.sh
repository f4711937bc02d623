#!/bin/sh
# The installed unit file: systemd-analyze verify accepts it; it has the
# readiness, sandboxing and device settings a lab box needs; it starts with no
# config file (no --config on ExecStart); and `systemd-analyze security`
# rates it 2.0 or lower. tests/e2e/systemd_sandbox.py tries its options on
# the daemon itself.
unit=${SHADEBENCH_UNIT:-systemd/shadebenchd.service}
daemon=${SHADEBENCHD:-./shadebenchd}
if ! command -v systemd-analyze >/dev/null 2>&1; then
    echo "SKIP: systemd-analyze is not installed"
    exit 77
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# verify wants ExecStart's program to exist: point it at the built daemon.
sed "s|^ExecStart=[^ ]*|ExecStart=$daemon|" "$unit" >"$tmp/shadebenchd.service"
failed=0
if ! systemd-analyze verify "$tmp/shadebenchd.service"; then
    echo "FAIL: systemd-analyze verify"
    failed=1
fi
for line in Type=notify DynamicUser=yes StateDirectory=shadebench ProtectSystem=strict \
    ProtectHome=yes PrivateTmp=yes NoNewPrivileges=yes "SupplementaryGroups=render video" \
    "DeviceAllow=char-drm rw" "DeviceAllow=char-nvidia-frontend rw" DevicePolicy=closed \
    Restart=on-failure CapabilityBoundingSet= "SystemCallFilter=@system-service"; do
    if ! grep -qx "$line" "$unit"; then
        echo "FAIL: $unit lacks $line"
        failed=1
    fi
done
# A missing config file must not stop the service: no --config on ExecStart.
if grep -q '^ExecStart=.*--config' "$unit"; then
    echo "FAIL: ExecStart passes --config, which make install does not create"
    failed=1
fi
# And the daemon does start without one (the default path may be absent).
SHADEBENCH_CONFIG= "$daemon" --listen 127.0.0.1:0 --state-dir "$tmp/state" \
    --port-file "$tmp/port" >"$tmp/log" 2>&1 &
pid=$!
i=0
while [ ! -s "$tmp/port" ] && [ $i -lt 600 ] && kill -0 $pid 2>/dev/null; do
    sleep 0.1
    i=$((i + 1))
done
if [ -s "$tmp/port" ]; then
    echo "ok: the daemon starts with no config file"
else
    echo "FAIL: the daemon does not start without a config file:"
    cat "$tmp/log"
    failed=1
fi
kill $pid 2>/dev/null
wait $pid 2>/dev/null
# The exposure score, offline (the unit need not be installed). Debian 12's
# systemd 252 prints "Overall exposure level for NAME: 1.5 OK".
score=$(systemd-analyze security --offline=yes "$tmp/shadebenchd.service" 2>/dev/null |
    sed -n 's/.*Overall exposure level for [^:]*: \([0-9.]*\).*/\1/p')
echo "systemd-analyze security --offline=yes: ${score:-none}"
if [ -z "$score" ] || ! awk "BEGIN { exit !($score <= 2.0) }"; then
    echo "FAIL: the unit's exposure is ${score:-unknown}, above 2.0"
    failed=1
fi
echo "systemd_unit: $failed failed"
exit $failed
