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
# Tests that read ../shared (real captures, the LPIPS network) skip when it is not beside the
# checkout, and the harness counts a skip as passed: they write themselves here, listed at the end.
export COGEO_SKIPPED_LOG="$(mktemp)"
report_skipped() {
  if [ -s "$COGEO_SKIPPED_LOG" ]; then
    echo "test.sh: $(sort -u "$COGEO_SKIPPED_LOG" | wc -l) test(s) skipped, their data missing (counted as passed above):" >&2
    sort -u "$COGEO_SKIPPED_LOG" | sed 's/^/  /' >&2
  fi
  rm -f "$COGEO_SKIPPED_LOG"
}
trap report_skipped EXIT
cargo test --release "$@"
