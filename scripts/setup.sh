#!/usr/bin/env bash
# Installs, with apt-get, only the system packages refrakt needs that are missing, and a
# Rust toolchain if there is none. Idempotent; prints nothing when everything is present.
#
#   mesa-vulkan-drivers     lavapipe, the CPU Vulkan driver (works with no GPU)
#   libvulkan1              the Vulkan loader
#   vulkan-validationlayers VK_LAYER_KHRONOS_validation, used by the tests and --validate
#   libshaderc-dev glslang-dev spirv-tools
#                           the system shaderc + glslang + SPIRV-Tools static libraries
#                           build.rs links (see .cargo/config.toml)
#   gcc g++ pkg-config      C/C++ toolchain and libstdc++ for the static shaderc link
#   libx11-6 libx11-xcb1 libxcursor1 libxi6 libxkbcommon0 libxkbcommon-x11-0
#                           what winit loads at run time for `refrakt view` on X11
#   xvfb                    a virtual X server: tests/viewer.rs opens its window there
#   xdotool x11-utils       drive and inspect the viewer's window by hand (xdotool, xwininfo)
set -euo pipefail

packages=(mesa-vulkan-drivers libvulkan1 vulkan-validationlayers libshaderc-dev glslang-dev
          spirv-tools gcc g++ pkg-config ca-certificates curl
          libx11-6 libx11-xcb1 libxcursor1 libxi6 libxkbcommon0 libxkbcommon-x11-0
          xvfb xdotool x11-utils)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  if [ "$(id -u)" -eq 0 ]; then sudo=(); else sudo=(sudo); fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo[@]}" apt-get update -qq
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null 2>&1 && [ -x "$HOME/.cargo/bin/cargo" ]; then
  export PATH="$HOME/.cargo/bin:$PATH"
fi
if ! command -v cargo >/dev/null 2>&1; then
  echo "setup: no cargo found; installing Rust with rustup" >&2
  curl --proto '=https' --tlsv1.2 -sSf https://sh.rustup.rs | sh -s -- -y --profile minimal -c clippy,rustfmt >&2
fi
