#!/bin/sh
# Regenerates the README's PBR captures (docs/pbr/*.png) with a built daemon:
#   docs/pbr/make_captures.sh build/shadebenchd
# Each capture is frame 1 of a one-frame --once job at 320x240.
set -eu
D=$1
OUT=$(dirname "$0")
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
cap() {
    name=$1
    shift
    printf '%s\n' "$*" >"$TMP/$name.json"
    "$D" --once "$TMP/$name.json" --out "$TMP/$name" >/dev/null 2>&1 || { echo "FAIL $name"; exit 1; }
    cp "$TMP/$name/frame-000001.png" "$OUT/$name.png"
    echo "$name: $*"
}
J='"frames":1,"warmup_frames":0,"capture_interval":1'
T='"preset":"teapots","width":320,"height":240'
cap teapots-phong "{$J,\"scene\":{$T,\"lights\":16}}"
cap teapots-pbr "{$J,\"look\":{\"lighting\":\"pbr\"},\"scene\":{$T,\"lights\":16}}"
cap teapots-ibl "{$J,\"look\":{\"lighting\":\"pbr\",\"ibl\":{\"probes\":3}},\"scene\":{$T,\"lights\":16}}"
cap teapots-full "{$J,\"technique\":\"clustered_deferred\",\"look\":{\"lighting\":\"pbr\",\"ibl\":{\"probes\":3},\"shadows\":{\"atlas\":4096}},\"scene\":{$T,\"lights\":80}}"
cap chart-ibl "{$J,\"look\":{\"lighting\":\"pbr\",\"ibl\":true},\"scene\":{\"preset\":\"chart\",\"width\":320,\"height\":240}}"
cap sphere-shadow "{$J,\"look\":{\"lighting\":\"pbr\",\"shadows\":true},\"scene\":{\"preset\":\"sphere\",\"roughness\":0.6,\"width\":320,\"height\":240}}"
cap furnace "{$J,\"look\":{\"lighting\":\"pbr\",\"ibl\":{\"environment\":\"uniform\",\"intensity\":0.5}},\"scene\":{\"preset\":\"sphere\",\"lights\":0,\"roughness\":1,\"width\":320,\"height\":240}}"
