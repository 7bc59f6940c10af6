#!/usr/bin/env bash
# Set up tolins from the repository root: the Debian packages it needs (only when run
# as root with apt-get, and only those missing), then a virtual environment in .venv
# with tolins installed editable, test extras included.
#
# mesa-vulkan-drivers: a software Vulkan driver (lavapipe) for the rerun viewer's
# headless screenshots (`tolins replay FILE.rrd --screenshot OUT.png`); libegl1 and
# libgl1-mesa-dri: headless OpenGL (EGL) for MuJoCo's renderer (`render_mode="rgb_array"`,
# dm_control's `physics.render`). Without them everything else works.
set -euo pipefail
cd "$(dirname "$0")/.."

DEBIAN_PACKAGES=(mesa-vulkan-drivers libegl1 libgl1-mesa-dri)

missing=()
for package in "${DEBIAN_PACKAGES[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$package")
    fi
done
if ((${#missing[@]})); then
    if [[ "$(id -u)" == 0 ]] && command -v apt-get >/dev/null; then
        echo "setup: installing ${missing[*]}" >&2
        if ! { apt-get update -qq &&
            DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
                "${missing[@]}" >/dev/null; }; then
            echo "setup: warning: could not install ${missing[*]}; headless screenshots of" \
                "recordings will not work" >&2
        fi
    else
        echo "setup: skipping ${missing[*]} (needs root and apt-get); headless screenshots" \
            "of recordings will not work until it is installed" >&2
    fi
fi

python3 -m venv .venv
.venv/bin/pip install -q -e '.[test]'
