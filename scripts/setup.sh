#!/usr/bin/env bash
# Installs what cogeo needs to build and test on Debian 12 / Ubuntu, and prepares the shaderc static
# library. Idempotent: does nothing that is already done. Sourced by scripts/test.sh and scripts/demo.sh.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

need_pkgs=()
for p in g++ libshaderc-dev glslang-dev spirv-tools mesa-vulkan-drivers vulkan-validationlayers libvulkan1; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || need_pkgs+=("$p")
done
if [ ${#need_pkgs[@]} -gt 0 ]; then
  echo "setup: installing ${need_pkgs[*]}" >&2
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${need_pkgs[@]}" >&2
fi

if ! command -v cargo >/dev/null 2>&1; then
  echo "setup: cargo not found; install Rust from rustup first" >&2
  exit 1
fi

# Debian's libshaderc.so is underlinked (glslang missing) and its libshaderc_combined.a lacks glslang,
# so shaderc-sys cannot link either. Merge the static archives into one complete libshaderc_combined.a;
# .cargo/config.toml points SHADERC_LIB_DIR here.
out="$root/.shaderc/lib"
if [ ! -f "$out/libshaderc_combined.a" ]; then
  libdir="$(dirname "$(dpkg -L libshaderc-dev | grep 'libshaderc_combined.a$' | head -n1)")"
  mkdir -p "$out"
  script="$(mktemp)"
  {
    echo "CREATE $out/libshaderc_combined.a.tmp"
    for l in shaderc_combined glslang MachineIndependent GenericCodeGen SPIRV HLSL OSDependent OGLCompiler \
             glslang-default-resource-limits SPIRV-Tools-opt SPIRV-Tools; do
      if [ -f "$libdir/lib$l.a" ]; then echo "ADDLIB $libdir/lib$l.a"; fi
    done
    echo "SAVE"
    echo "END"
  } > "$script"
  ar -M < "$script"
  rm -f "$script"
  mv "$out/libshaderc_combined.a.tmp" "$out/libshaderc_combined.a"
  echo "setup: merged shaderc static archives into $out/libshaderc_combined.a" >&2
fi
