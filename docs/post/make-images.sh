#!/bin/sh
# Regenerates the README's before/after captures of each post effect: one
# frame of the thesis scene (moving lights, frame 30) per look, rendered by
# forward with `shadebenchd --once`. Usage: docs/post/make-images.sh [DAEMON]
set -eu
cd "$(dirname "$0")"
daemon=${1:-../../build/shadebenchd}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
shot() {
    name=$1
    look=$2
    technique=${3:-forward}
    printf '{"technique": "%s", "frames": 30, "warmup_frames": 0, "capture_interval": 30,
      "scene": {"width": 360, "height": 240, "dynamic": true}, "look": %s}\n' \
        "$technique" "$look" >"$tmp/$name.json"
    "$daemon" --once "$tmp/$name.json" --out "$tmp/$name" >"$tmp/$name.log" 2>&1 ||
        { cat "$tmp/$name.log"; exit 1; }
    cp "$tmp/$name/frame-000030.png" "$name.png"
    echo "$name.png: $look"
}
shot none '{}'
shot bloom '{"post": [{"bloom": {"threshold": 0.4, "intensity": 3, "radius": 8}}]}'
shot bloom_mip '{"post": [{"bloom": {"threshold": 0.4, "intensity": 6, "radius": 4, "downsample": 3}}]}'
shot toon_sobel '{"post": [{"toon": {"edges": "sobel"}}]}'
shot toon_depth_diff '{"post": [{"toon": {"edges": "depth_diff", "thickness": 2}}]}'
shot unlit '{}' unlit
shot unlit_ssao '{"post": [{"ssao": {"samples": 32, "radius": 1.5}}]}' unlit
shot ssao '{"post": [{"ssao": {"samples": 32, "radius": 1.5}}]}'
shot aces '{"tonemap": "aces", "exposure": 2}'
shot reinhard '{"tonemap": "reinhard"}'
shot chain '{"post": [{"bloom": {"threshold": 0.5}}, {"toon": {"edges": "sobel"}}, "ssao"], "tonemap": "aces"}'
