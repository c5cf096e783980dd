#!/usr/bin/env bash
# Prepares, on this machine, what scripts/gpu_checks.sh needs on a lent NVIDIA machine (device
# tool): run it here, then call the device with carry [".gl", ".gpu", ".whl"] and the command
# `bash scripts/gpu_checks.sh`. Needs network access here (apt and pip downloads).
#   .gpu/bin.tar.xz  stripped cogeo, every test binary, the render/sort/train benches
#   .gpu/target_dir  the CARGO_TARGET_DIR they were built in (the test binaries find cogeo there)
#   .gpu/shared-*.tar.xz  the parts of ../shared the tests read, one xz tarball each; a part that
#                    would take the call past the device's 64 MiB is left out and named in
#                    .gpu/left_out.txt (its tests then skip, and the harness counts a skip as passed)
#   .gl/*.deb        the Vulkan loader and libglvnd (NVIDIA's ICD needs both)
#   .whl/            gsplat's wheel (its CUDA kernels compile there on first use, 65-92 s)
set -euo pipefail
cd "$(dirname "$0")/.."
for d in .gl .gpu .whl; do grep -qx "/$d/" .git/info/exclude 2>/dev/null || echo "/$d/" >> .git/info/exclude; done
target=${CARGO_TARGET_DIR:-$PWD/target}
export CARGO_TARGET_DIR=$target

executables() { python3 -c '
import json, sys
for line in sys.stdin:
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m.get("executable"):
        print(m["target"]["kind"][0], m["target"]["name"], m["executable"])'; }

cargo build --release
rm -rf .gpu && mkdir -p .gpu/pack/t/tests .gpu/pack/t/bench
cp "$target/release/cogeo" .gpu/pack/t/
cargo test --release --no-run --message-format=json 2>/dev/null | executables | while read -r kind name exe; do
    [ "$exe" = "$target/release/cogeo" ] && continue # the binary itself, copied above: no test harness
    cp "$exe" ".gpu/pack/t/tests/$name-$(basename "$exe" | sed 's/.*-//')"
done
cargo bench --no-run --message-format=json 2>/dev/null | executables | while read -r kind name exe; do
    case $name in render|sort|train) cp "$exe" ".gpu/pack/t/bench/$name" ;; esac
done
strip .gpu/pack/t/cogeo .gpu/pack/t/tests/* .gpu/pack/t/bench/*
(cd .gpu/pack && tar cf - t | xz -T0 -6 > ../bin.tar.xz)
rm -rf .gpu/pack
echo "$target" > .gpu/target_dir

rm -rf .gl && mkdir -p .gl /tmp/amd64/partial
o=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64)
apt-get "${o[@]}" update > /dev/null
(cd .gl && apt-get "${o[@]}" download libvulkan1 libglvnd0 libegl1 libgl1 libglx0 libgles2 libopengl0 2>&1 | grep -v unsandboxed || true)

rm -rf .whl && mkdir -p .whl
python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
    --platform manylinux_2_28_x86_64 --platform manylinux2014_x86_64 --platform any -d .whl gsplat==1.5.3

# The shared data last, into what the 64 MiB leave: the working tree (tracked files; untracked
# ones that are not ignored travel too, so the check counts them) and the carried folders so far.
limit=$(( 64 * 1024 * 1024 - 256 * 1024 ))
tree=$( { git ls-files -z; git ls-files -z --others --exclude-standard; } | xargs -0 -r du -cb 2>/dev/null | awk '$2 == "total" {s += $1} END {print s + 0}')
used=$(( tree + $(du -sb .gpu .gl .whl | awk '{s += $1} END {print s}') ))
: > .gpu/left_out.txt
# name and paths under ../shared, most needed first: the statue photo and the LPIPS network (eval),
# the real splat (ply_io, render_real_and_large), the statue's COLMAP model (cli_and_cameras),
# the cup capture (cup: trains on the GPU), the statue's photos (dataset: the rotation check)
for part in "statue-photo data/statue/images_2/IMG_2707.png" "lpips models/lpips_alex_v0.1.onnx" \
    "splats data/splats/guitar.ply" "statue-sparse data/statue/sparse" "cup data/cup" \
    "statue-images data/statue/images_2"; do
    set -- $part
    tar cf - -C ../shared "$2" | xz -T0 -6 > ".gpu/shared-$1.tar.xz"
    size=$(stat -c %s ".gpu/shared-$1.tar.xz")
    if [ $(( used + size )) -gt $limit ]; then
        rm ".gpu/shared-$1.tar.xz"
        echo "$1 ($2, $size bytes compressed): left out, over the 64 MiB" | tee -a .gpu/left_out.txt
    else
        used=$(( used + size ))
    fi
done
du -sh .gpu .gl .whl
echo "ready: $(( used / 1048576 )) MiB of 64 travel (tree $(( tree / 1048576 )) MiB); carry .gl .gpu .whl"
