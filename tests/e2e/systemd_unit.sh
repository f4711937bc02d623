#!/bin/sh
# The installed unit file: systemd-analyze verify accepts it, and it has the
# readiness, sandboxing and device settings a lab box needs.
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
    "DeviceAllow=char-drm rw" Restart=on-failure; do
    if ! grep -qx "$line" "$unit"; then
        echo "FAIL: $unit lacks $line"
        failed=1
    fi
done
echo "systemd_unit: $failed failed"
exit $failed
