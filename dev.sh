#!/usr/bin/env bash
# Set up (or reuse) .venv at the repo root, with the system libraries transfertwin needs,
# then run the main job (`./dev.sh run`), the tests (`./dev.sh test`) or any command in
# the environment (`./dev.sh exec CMD...`).
set -euo pipefail
cd "$(dirname "$0")"

need_apt=()
# Headless rendering (EGL via Mesa, OSMesa as fallback); Open3D links libGL, libX11 and libusb.
for lib in libEGL.so.1 libEGL_mesa.so.0 libOSMesa.so libGL.so.1 libX11.so.6 libusb-1.0.so.0 \
    libgomp.so.1; do
    if ! ldconfig -p 2>/dev/null | grep -q "$lib"; then
        case "$lib" in
            libEGL.so.1) need_apt+=(libegl1) ;;
            libEGL_mesa.so.0) need_apt+=(libegl-mesa0 libgl1-mesa-dri) ;;
            libOSMesa.so) need_apt+=(libosmesa6) ;;
            libGL.so.1) need_apt+=(libgl1) ;;
            libX11.so.6) need_apt+=(libx11-6) ;;
            libusb-1.0.so.0) need_apt+=(libusb-1.0-0) ;;
            libgomp.so.1) need_apt+=(libgomp1) ;;
        esac
    fi
done
# The browser tests of the web console drive Debian's chromium (Playwright, no download).
command -v chromium >/dev/null 2>&1 || need_apt+=(chromium)
if [ ${#need_apt[@]} -gt 0 ]; then
    echo "dev.sh: installing system packages: ${need_apt[*]}" >&2
    SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq && $SUDO env DEBIAN_FRONTEND=noninteractive \
        apt-get install -y -qq --no-install-recommends "${need_apt[@]}" >/dev/null
fi

PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    "$PY" -m venv .venv
fi
stamp=.venv/.transfertwin-installed
if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ]; then
    .venv/bin/python -m pip install -q --upgrade pip
    .venv/bin/python -m pip install -q -e ".[dev]"
    touch "$stamp"
fi

cmd=${1:-run}
shift || true
case "$cmd" in
    run)
        # The main job: the quick full-state study (resumable), then its analysis/report.
        mkdir -p out
        .venv/bin/transfertwin study run --db out/quick.sqlite --preset quick "$@"
        exec .venv/bin/transfertwin analyze out/quick.sqlite --out out/quick-report ;;
    test) exec .venv/bin/python -m pytest -q "$@" ;;
    exec) exec "$@" ;;
    *) echo "usage: ./dev.sh run|test|exec CMD..." >&2; exit 2 ;;
esac
