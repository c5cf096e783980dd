#!/usr/bin/env bash
# The main job on built-in data: generates a synthetic multi-object scene, trains it, tags it,
# removes two objects and evaluates against the exact ground truth, into demo_out/.
# Installs what is missing first (scripts/setup.sh). Extra arguments go to `cogeo demo` (--quick).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
# the real LPIPS network, when the shared models are beside the project, scores the fill
extra=()
lpips="$root/../shared/models/lpips_alex_v0.1.onnx"
if [ -f "$lpips" ]; then extra=(--lpips-model "$lpips"); fi
cargo run --release --quiet -- demo "${extra[@]}" "$@"
