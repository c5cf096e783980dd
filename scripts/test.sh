#!/usr/bin/env bash
# Runs the whole test suite with the Khronos validation layer on (every test fails on any validation
# message). Installs what is missing first (scripts/setup.sh). Extra arguments go to `cargo test`.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
export COGEO_VALIDATE=1
# The Vulkan loader warns about a missing XDG_RUNTIME_DIR in minimal environments; give it one.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
cargo test --release "$@"
