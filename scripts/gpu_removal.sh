#!/usr/bin/env bash
# `cogeo remove` at real size on a lent NVIDIA machine (device tool): the removal speed bench's
# scene (the statue at images_2, trained 800 iterations and tagged), this build against an older
# binary, alternately, as `cargo bench --bench removal_speed -- --baseline` does on lavapipe.
# Prepare here:  bash scripts/gpu_removal.sh --pack OLD_COGEO   (writes .rm/, about 35 MiB)
# Run there:     bash scripts/gpu_removal.sh   (carry .gl .rm; .gl from scripts/gpu_pack.sh)
# Writes under $OUT: devices.txt, removal.log, and each run's report as report-NAME-R.json.
set -u
cd "$(dirname "$0")/.."
if [ "${1:-}" = --pack ]; then
    set -e
    old=${2:?"--pack OLD_COGEO: the baseline binary"}
    grep -qx "/.rm/" .git/info/exclude || echo "/.rm/" >> .git/info/exclude
    target=${CARGO_TARGET_DIR:-$PWD/target}
    tagged=target/bench-cache/statue/speed-images_2-800/tagged.ply
    [ -f "$tagged" ] || { echo "$tagged: missing; run cargo bench --bench removal_speed once first"; exit 1; }
    rm -rf .rm && mkdir -p .rm/statue
    cp "$target/release/cogeo" .rm/cogeo && cp "$old" .rm/baseline && strip .rm/cogeo .rm/baseline
    cp -r ../shared/data/statue/images_2 ../shared/data/statue/sparse .rm/statue/
    cp "$tagged" .rm/tagged.ply
    du -sh .rm
    exit 0
fi
t0=$(date +%s)
elapsed() { echo $(( $(date +%s) - t0 )); }
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
icd=$(find /usr/local/nvidia /usr/share/vulkan /etc/vulkan -name 'nvidia_icd*.json' 2>/dev/null | head -1)
[ -n "$icd" ] && export VK_DRIVER_FILES=$icd
export XDG_RUNTIME_DIR=/tmp COGEO_VALIDATE=0
{ nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv; nproc; .rm/cogeo devices; } > "$OUT/devices.txt" 2>&1
cat "$OUT/devices.txt"
deadline=${DEADLINE:-400}
for r in 1 2 3; do
    for name in cogeo baseline; do
        if [ "$(elapsed)" -gt "$deadline" ]; then echo "past ${deadline} s: no run $r of $name"; continue; fi
        out=/tmp/rm-$name-$r
        s=$(date +%s.%N)
        ".rm/$name" remove --scene .rm/tagged.ply --data .rm/statue --images images_2 --labels 1 --out "$out" \
            > "$OUT/remove-$name-$r.log" 2>&1
        rc=$?
        e=$(date +%s.%N)
        echo "$name run $r: exit $rc, wall $(python3 -c "print(round($e - $s, 2))") s (at $(elapsed) s)"
        cp "$out/report.json" "$OUT/report-$name-$r.json" 2>/dev/null
    done
done | tee "$OUT/removal.log"
python3 - "$OUT" <<'EOF'
import json, glob, sys, os
for f in sorted(glob.glob(os.path.join(sys.argv[1], "report-*.json"))):
    r = json.load(open(f)); s = r.get("seconds", {})
    print(os.path.basename(f), "total", round(r.get("total_seconds", 0), 2),
          {k: round(v, 2) for k, v in s.items() if isinstance(v, (int, float))})
EOF
echo "done at $(elapsed) s"
