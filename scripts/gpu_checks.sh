#!/usr/bin/env bash
# The GPU checks of ../shared/docs/gpu.md in one command, for a lent NVIDIA machine (device tool).
# Prepare here with scripts/gpu_pack.sh (binaries, the shared data the tests read, the Vulkan
# loader and libglvnd .debs, gsplat's wheel), then run there as:  bash scripts/gpu_checks.sh
# (carry .gl .gpu .whl). The test binaries expect the paths they were built with: the script
# recreates /work/main (this checkout) and the target folder named in .gpu/target_dir.
# Writes under $OUT: devices.txt, bench.log, clocks.csv (SM clock and load every 200 ms during the
# benches), tests.log, gsplat.log, gsplat_build.log, gsplat.json, results.tar.
set -u
t0=$(date +%s)
elapsed() { echo $(( $(date +%s) - t0 )); }
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"

for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
icd=$(find /usr/local/nvidia /usr/share/vulkan /etc/vulkan -name 'nvidia_icd*.json' 2>/dev/null | head -1)
echo "Vulkan ICD: ${icd:-none found}"; [ -n "$icd" ] && export VK_DRIVER_FILES=$icd
export XDG_RUNTIME_DIR=/tmp COGEO_VALIDATE=0 RUST_BACKTRACE=1

# gsplat compiles its CUDA kernels on first use: start that now, beside the cogeo runs.
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site
(MAX_JOBS=12 TORCH_CUDA_ARCH_LIST=9.0 nice -n 5 python3 -c "from gsplat.cuda._backend import _C; print('built', _C)" \
    > "$OUT/gsplat_build.log" 2>&1; echo "build finished at $(elapsed) s" >> "$OUT/gsplat_build.log") &
build=$!

# The binaries expect the paths they were built with.
tar xJf .gpu/bin.tar.xz -C /tmp
target=$(cat .gpu/target_dir 2>/dev/null || echo /tmp/tgt3)
mkdir -p /work "$target/release"
[ "$PWD" = /work/main ] || ln -sfn "$PWD" /work/main
mkdir -p /tmp/shared && for f in .gpu/shared-*.tar.xz; do tar xJf "$f" -C /tmp/shared; done
[ -e /work/shared ] || ln -sfn /tmp/shared /work/shared
cp /tmp/t/cogeo "$target/release/cogeo"
ort=$(python3 -c 'import onnxruntime, os, glob; print(sorted(glob.glob(os.path.dirname(onnxruntime.__file__) + "/capi/libonnxruntime.so*"))[0])' 2>/dev/null)
[ -n "$ort" ] && export ORT_DYLIB_PATH=$ort

{ nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.max.sm --format=csv; /tmp/t/cogeo devices; } > "$OUT/devices.txt" 2>&1
cat "$OUT/devices.txt"
if ! /tmp/t/cogeo devices >/dev/null 2>&1; then
    echo "no Vulkan device: loader diagnostics follow"; cat "$icd"; ldconfig -p | grep -iE "nvidia|GLdispatch" | head
    VK_LOADER_DEBUG=error,warn,driver /tmp/t/cogeo devices 2>&1 | tail -20
    exit 1
fi

# the SM clock beside the benches: is the render path's slowness (bench/RESULTS.md) a low clock?
nvidia-smi --query-gpu=timestamp,clocks.sm,utilization.gpu --format=csv -lms 200 > "$OUT/clocks.csv" 2>&1 &
clocks=$!
{
    echo "== render ($(elapsed) s)"
    timeout 120 /tmp/t/bench/render --sizes 1000000,3000000 --resolutions 1920x1080 --frames 10 --no-results --write-scenes /tmp/scenes
    echo "== sort ($(elapsed) s)"
    timeout 60 /tmp/t/bench/sort --no-results
    echo "== train ($(elapsed) s)"
    timeout 120 /tmp/t/bench/train --sizes 1000000,3000000 --resolution 1920x1080 --iters 10 --full-sh --no-results
    echo "== benches done ($(elapsed) s)"
} > "$OUT/bench.log" 2>&1
kill $clocks 2>/dev/null
grep -E "^device|GPU total|GPU [0-9.]+ ms|ms/iter|iteration|Gaussians" "$OUT/bench.log" | head -30

# The whole test suite, one binary at a time; stop starting new ones past the deadline. A test
# whose shared data is missing skips (counted as passed): with every part carried that fails it.
export COGEO_SKIPPED_LOG=/tmp/skipped.txt
[ -s .gpu/left_out.txt ] || export COGEO_REQUIRE_SHARED=1
for t in /tmp/t/tests/*; do
    if [ "$(elapsed)" -gt 330 ]; then echo "SKIPPED (deadline): $(basename "$t")" >> "$OUT/tests.log"; continue; fi
    echo "== $(basename "$t") ($(elapsed) s)" >> "$OUT/tests.log"
    timeout 100 "$t" --test-threads 8 >> "$OUT/tests.log" 2>&1; echo "exit $?" >> "$OUT/tests.log"
done
# a test whose shared data did not travel skips, and the harness counts it as passed: say which
[ -s .gpu/left_out.txt ] && sed 's/^/SHARED DATA NOT CARRIED (its tests skipped): /' .gpu/left_out.txt >> "$OUT/tests.log"
[ -s /tmp/skipped.txt ] && sed 's/^/SKIPPED (no data): /' /tmp/skipped.txt >> "$OUT/tests.log"
grep -E "^== |^test result|exit [^0]|FAILED|panicked|SKIPPED|NOT CARRIED" "$OUT/tests.log" | grep -v "exit 0" | head -80
# gradients crashed at a thread's exit on an H200 (contexts dropped on 8 threads; bench/JOURNAL.md,
# second GPU run): run it again a few times, the exit status of each
for i in 1 2 3 4; do
    [ "$(elapsed)" -gt 360 ] && break
    timeout 60 /tmp/t/tests/gradients-* --test-threads 8 > /dev/null 2>&1; echo "gradients again, run $i: exit $?"
done | tee -a "$OUT/tests.log"

# gsplat on the same scenes and cameras.
while kill -0 $build 2>/dev/null && [ "$(elapsed)" -lt 470 ]; do sleep 2; done
tail -5 "$OUT/gsplat_build.log"
timeout $(( 530 - $(elapsed) )) python3 scripts/gsplat_peer.py /tmp/scenes --json "$OUT/gsplat.json" > "$OUT/gsplat.log" 2>&1
tail -8 "$OUT/gsplat.log"
tar cf "$OUT/results.tar" -C bench/results . 2>/dev/null
echo "done at $(elapsed) s"
