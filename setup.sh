#!/usr/bin/env bash
# One-step set-up of `clear` on a fresh machine with Python 3.11 and pip:
# system libraries open3d links (the tests' independent PCD reader; when missing and we
# may install them), a virtual
# environment in .venv, and the package with its test extras. Safe to run again.
set -euo pipefail
cd "$(dirname "$0")"

# open3d links libusb, libGL/libEGL, libX11, libudev and libgomp; a bare Debian/Ubuntu lacks some.
need=()
for pair in libusb-1.0.so.0:libusb-1.0-0 libGL.so.1:libgl1 libEGL.so.1:libegl1 \
            libX11.so.6:libx11-6 libudev.so.1:libudev1 libgomp.so.1:libgomp1; do
  lib=${pair%%:*}; pkg=${pair##*:}
  if ! ldconfig -p 2>/dev/null | grep -q "$lib"; then need+=("$pkg"); fi
done
if [ ${#need[@]} -gt 0 ]; then
  if command -v apt-get >/dev/null 2>&1; then
    sudo_cmd=""; [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
    echo "setup: installing system packages: ${need[*]}" >&2
    $sudo_cmd apt-get update -qq >&2
    DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${need[@]}" >&2
  else
    echo "setup: please install the system libraries for: ${need[*]}" >&2
  fi
fi

PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  "$PY" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip >&2
.venv/bin/python -m pip install -q -e ".[test]" >&2
# Byte-compile clear's own modules: an editable install is otherwise compiled on every
# start where PYTHONDONTWRITEBYTECODE is set (0.2 s of every cold `clear` call).
.venv/bin/python -m compileall -q clearcli >&2
echo "setup: done; the command is .venv/bin/clear" >&2
