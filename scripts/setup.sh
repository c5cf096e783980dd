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

# onnxruntime for the optional ONNX models (inpainting, depth, denoiser; tests use tiny models they
# build): the shared library of the PyPI wheel, unpacked where cogeo looks for it by default
# (src/onnx.rs). ORT_DYLIB_PATH overrides that location.
ort_version=1.31.1
ort_dir="${XDG_CACHE_HOME:-$HOME/.cache}/cogeo/onnxruntime"
if [ ! -f "$ort_dir/libonnxruntime.so.$ort_version" ]; then
  if ! python3 -m pip --version >/dev/null 2>&1; then
    echo "setup: installing python3-pip (to fetch the onnxruntime wheel)" >&2
    sudo_cmd=""
    [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
    $sudo_cmd apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends python3-pip >&2
  fi
  tmp="$(mktemp -d)"
  python3 -m pip download --quiet --no-deps --only-binary=:all: --platform "manylinux_2_28_$(uname -m)" \
    --python-version 3.11 "onnxruntime==$ort_version" -d "$tmp" >&2
  mkdir -p "$ort_dir"
  python3 - "$tmp" "$ort_dir" "$ort_version" <<'PY'
import glob, os, sys, zipfile
tmp, out, version = sys.argv[1:4]
wheel = glob.glob(os.path.join(tmp, "onnxruntime-*.whl"))[0]
with zipfile.ZipFile(wheel) as z:
    for name in z.namelist():
        base = os.path.basename(name)
        if base in (f"libonnxruntime.so.{version}", "libonnxruntime_providers_shared.so"):
            dest = os.path.join(out, base)
            with z.open(name) as src, open(dest + ".tmp", "wb") as dst:
                dst.write(src.read())
            os.replace(dest + ".tmp", dest)
PY
  rm -rf "$tmp"
  echo "setup: installed onnxruntime $ort_version into $ort_dir" >&2
fi
